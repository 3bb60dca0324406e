#include "lightstage/hw/ffs_descriptors.hpp"

#include "lightstage/hw/usb_interface.hpp"

#include <endian.h>
#include <linux/usb/ch9.h>
#include <linux/usb/functionfs.h>

#include <cstring>
#include <string>

namespace lightstage::hw {
namespace {

// The kernel's packed structs give the exact wire layout; memcpy copies them
// into the blob without alignment concerns.
template <typename T>
void append(std::vector<std::uint8_t>& out, const T& value) {
  const auto at = out.size();
  out.resize(at + sizeof(T));
  std::memcpy(out.data() + at, &value, sizeof(T));
}

void append_le32(std::vector<std::uint8_t>& out, std::uint32_t value) { append(out, htole32(value)); }

void set_le32(std::vector<std::uint8_t>& out, std::size_t at, std::uint32_t value) {
  const std::uint32_t le = htole32(value);
  std::memcpy(out.data() + at, &le, sizeof le);
}

constexpr std::uint32_t kDescriptorsPerSpeed = 3;  // interface, bulk IN, bulk OUT

void append_function(std::vector<std::uint8_t>& out, std::uint16_t max_packet) {
  usb_interface_descriptor interface {};
  interface.bLength = USB_DT_INTERFACE_SIZE;
  interface.bDescriptorType = USB_DT_INTERFACE;
  interface.bInterfaceNumber = 0;  // FunctionFS renumbers within the configuration
  interface.bAlternateSetting = 0;
  interface.bNumEndpoints = 2;
  interface.bInterfaceClass = usb::kInterfaceClass;
  interface.bInterfaceSubClass = usb::kInterfaceSubclass;
  interface.bInterfaceProtocol = usb::kInterfaceProtocol;
  interface.iInterface = 1;  // the first string of ffs_strings()
  append(out, interface);
  for (const std::uint8_t address : {usb::kBulkInAddress, usb::kBulkOutAddress}) {
    usb_endpoint_descriptor_no_audio endpoint{};
    endpoint.bLength = USB_DT_ENDPOINT_SIZE;
    endpoint.bDescriptorType = USB_DT_ENDPOINT;
    endpoint.bEndpointAddress = address;
    endpoint.bmAttributes = USB_ENDPOINT_XFER_BULK;
    endpoint.wMaxPacketSize = htole16(max_packet);
    endpoint.bInterval = 0;
    append(out, endpoint);
  }
}

}  // namespace

std::vector<std::uint8_t> ffs_descriptors() {
  std::vector<std::uint8_t> out;
  append_le32(out, FUNCTIONFS_DESCRIPTORS_MAGIC_V2);
  append_le32(out, 0);  // length, set below
  append_le32(out, FUNCTIONFS_HAS_FS_DESC | FUNCTIONFS_HAS_HS_DESC);
  append_le32(out, kDescriptorsPerSpeed);  // fs_count
  append_le32(out, kDescriptorsPerSpeed);  // hs_count
  append_function(out, usb::kFullSpeedMaxPacket);
  append_function(out, usb::kHighSpeedMaxPacket);
  set_le32(out, 4, static_cast<std::uint32_t>(out.size()));
  return out;
}

std::vector<std::uint8_t> ffs_strings() {
  std::vector<std::uint8_t> out;
  append_le32(out, FUNCTIONFS_STRINGS_MAGIC);
  append_le32(out, 0);           // length, set below
  append_le32(out, 1);           // str_count
  append_le32(out, 1);           // lang_count
  append(out, htole16(0x0409));  // en-US
  const std::string name = usb::kInterfaceName;
  out.insert(out.end(), name.begin(), name.end());
  out.push_back(0);
  set_le32(out, 4, static_cast<std::uint32_t>(out.size()));
  return out;
}

}  // namespace lightstage::hw
