// The FunctionFS blobs are parsed back byte by byte, by offsets taken from
// linux/usb/functionfs.h and the USB 2.0 spec (chapter 9), not from the code
// that wrote them: a layout slip would make the kernel refuse the function.
#include "lightstage/hw/ffs_descriptors.hpp"
#include "lightstage/hw/usb_interface.hpp"

#include <gtest/gtest.h>
#include <linux/usb/functionfs.h>

#include <cstdint>
#include <string>
#include <vector>

namespace lightstage::hw {
namespace {

std::uint32_t le32(const std::vector<std::uint8_t>& blob, std::size_t at) {
  return static_cast<std::uint32_t>(blob.at(at)) | static_cast<std::uint32_t>(blob.at(at + 1)) << 8 |
         static_cast<std::uint32_t>(blob.at(at + 2)) << 16 |
         static_cast<std::uint32_t>(blob.at(at + 3)) << 24;
}

std::uint16_t le16(const std::vector<std::uint8_t>& blob, std::size_t at) {
  return static_cast<std::uint16_t>(blob.at(at) | blob.at(at + 1) << 8);
}

struct Endpoint {
  std::uint8_t address;
  std::uint8_t attributes;
  std::uint16_t max_packet;
};

struct Speed {
  std::uint8_t interface_class = 0, subclass = 0, protocol = 0, endpoint_count = 0, name_index = 0;
  std::vector<Endpoint> endpoints;
};

// Parses `count` descriptors from `at`, advancing it.
Speed parse_speed(const std::vector<std::uint8_t>& blob, std::size_t& at, std::uint32_t count) {
  Speed speed;
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::uint8_t length = blob.at(at);
    const std::uint8_t type = blob.at(at + 1);
    if (i == 0) {
      EXPECT_EQ(type, 0x04) << "first descriptor is not an interface";  // USB_DT_INTERFACE
      EXPECT_EQ(length, 9);
      EXPECT_EQ(blob.at(at + 3), 0) << "bAlternateSetting";
      speed.endpoint_count = blob.at(at + 4);
      speed.interface_class = blob.at(at + 5);
      speed.subclass = blob.at(at + 6);
      speed.protocol = blob.at(at + 7);
      speed.name_index = blob.at(at + 8);
    } else {
      EXPECT_EQ(type, 0x05) << "descriptor " << i << " is not an endpoint";  // USB_DT_ENDPOINT
      EXPECT_EQ(length, 7);
      speed.endpoints.push_back({blob.at(at + 2), blob.at(at + 3), le16(blob, at + 4)});
      EXPECT_EQ(blob.at(at + 6), 0) << "bInterval of a bulk endpoint";
    }
    at += length;
  }
  return speed;
}

TEST(FfsDescriptors, HeaderFollowsTheV2Layout) {
  const auto blob = ffs_descriptors();
  ASSERT_GE(blob.size(), 20u);
  EXPECT_EQ(le32(blob, 0), 3u);  // FUNCTIONFS_DESCRIPTORS_MAGIC_V2
  EXPECT_EQ(le32(blob, 0), static_cast<std::uint32_t>(FUNCTIONFS_DESCRIPTORS_MAGIC_V2));
  EXPECT_EQ(le32(blob, 4), blob.size()) << "length must cover the whole blob";
  EXPECT_EQ(le32(blob, 8), 3u);  // HAS_FS_DESC | HAS_HS_DESC, nothing else (no eventfd field follows)
  EXPECT_EQ(le32(blob, 12), 3u) << "fs_count";
  EXPECT_EQ(le32(blob, 16), 3u) << "hs_count";
  // 20 bytes of header, then per speed: interface (9) + two endpoints (7 each).
  EXPECT_EQ(blob.size(), 20u + 2 * (9 + 7 + 7));
}

TEST(FfsDescriptors, BothSpeedsDescribeOneVendorInterfaceWithBulkInAndOut) {
  const auto blob = ffs_descriptors();
  std::size_t at = 20;
  const Speed full = parse_speed(blob, at, le32(blob, 12));
  const Speed high = parse_speed(blob, at, le32(blob, 16));
  EXPECT_EQ(at, blob.size()) << "bytes left after the descriptors";
  for (const Speed* speed : {&full, &high}) {
    EXPECT_EQ(speed->interface_class, 0xff);
    EXPECT_EQ(speed->subclass, usb::kInterfaceSubclass);
    EXPECT_EQ(speed->protocol, usb::kInterfaceProtocol);
    EXPECT_EQ(speed->endpoint_count, 2);
    EXPECT_EQ(speed->name_index, 1) << "iInterface: the first string";
    ASSERT_EQ(speed->endpoints.size(), 2u);
    // ep1 (the first endpoint file) is IN, ep2 OUT; both bulk.
    EXPECT_EQ(speed->endpoints[0].address, 0x81);
    EXPECT_EQ(speed->endpoints[1].address, 0x02);
    for (const auto& endpoint : speed->endpoints) EXPECT_EQ(endpoint.attributes, 0x02) << "bulk";
  }
  for (const auto& endpoint : full.endpoints) EXPECT_EQ(endpoint.max_packet, 64);
  for (const auto& endpoint : high.endpoints) EXPECT_EQ(endpoint.max_packet, 512);
}

TEST(FfsDescriptors, StringsHoldTheInterfaceNameInEnglish) {
  const auto blob = ffs_strings();
  ASSERT_GE(blob.size(), 18u);
  EXPECT_EQ(le32(blob, 0), static_cast<std::uint32_t>(FUNCTIONFS_STRINGS_MAGIC));
  EXPECT_EQ(le32(blob, 4), blob.size());
  EXPECT_EQ(le32(blob, 8), 1u) << "str_count";
  EXPECT_EQ(le32(blob, 12), 1u) << "lang_count";
  EXPECT_EQ(le16(blob, 16), 0x0409);
  const std::string name(blob.begin() + 18, blob.end() - 1);
  EXPECT_EQ(name, usb::kInterfaceName);
  EXPECT_EQ(blob.back(), 0) << "strings are NUL-terminated";
}

}  // namespace
}  // namespace lightstage::hw
