// usb: URIs, independent of libusb so every build can parse and report them.
#include "lightstage/common/error.hpp"
#include "lightstage/hw/usb_link.hpp"

#include <fmt/format.h>

#include <charconv>

namespace lightstage::hw {
namespace {

constexpr const char* kForm = "usb:VID:PID[:SERIAL], VID and PID in hex, e.g. usb:1209:0001";

std::uint16_t parse_hex16(const std::string& uri, const std::string& text, const char* what) {
  unsigned value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value, 16);
  if (text.empty() || text.size() > 4 || ec != std::errc() || end != text.data() + text.size()) {
    fail("'{}': {} '{}' is not 1-4 hex digits (expected {})", uri, what, text, kForm);
  }
  return static_cast<std::uint16_t>(value);
}

}  // namespace

std::string UsbDeviceId::uri() const {
  return serial ? fmt::format("usb:{:04x}:{:04x}:{}", vendor_id, product_id, *serial)
                : fmt::format("usb:{:04x}:{:04x}", vendor_id, product_id);
}

UsbDeviceId parse_usb_uri(const std::string& uri) {
  if (uri.rfind("usb:", 0) != 0) fail("'{}' is not a usb: URI (expected {})", uri, kForm);
  const std::size_t vid_end = uri.find(':', 4);
  if (vid_end == std::string::npos) fail("'{}': no product ID (expected {})", uri, kForm);
  const std::size_t pid_end = uri.find(':', vid_end + 1);
  UsbDeviceId id;
  id.vendor_id = parse_hex16(uri, uri.substr(4, vid_end - 4), "vendor ID");
  id.product_id = parse_hex16(
      uri, uri.substr(vid_end + 1, pid_end == std::string::npos ? std::string::npos : pid_end - vid_end - 1),
      "product ID");
  if (pid_end != std::string::npos) {
    id.serial = uri.substr(pid_end + 1);
    if (id.serial->empty())
      fail("'{}': empty serial number (leave out the last ':' to take any device)", uri);
  }
  return id;
}

}  // namespace lightstage::hw
