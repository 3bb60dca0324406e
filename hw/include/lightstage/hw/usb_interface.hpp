#pragma once
// What the controller's USB function looks like, shared by the device side
// (ffs:, FunctionFS descriptors) and the host side (usb:, libusb), so both
// agree on how to find the interface and its endpoints.
//
// One vendor-specific interface with two bulk endpoints carrying the framed
// protocol (common/framing.hpp) as a plain byte stream in each direction.

#include <cstdint>

namespace lightstage::hw::usb {

inline constexpr std::uint8_t kInterfaceClass = 0xff;     // vendor specific
inline constexpr std::uint8_t kInterfaceSubclass = 0x4c;  // 'L'
inline constexpr std::uint8_t kInterfaceProtocol = 0x53;  // 'S': the framing of common/framing.hpp
inline constexpr const char* kInterfaceName = "Lightstage dome controller";

// Endpoint numbers in the FunctionFS descriptors: ep1 is the first endpoint
// file (bulk IN, controller -> host), ep2 the second (bulk OUT, host -> controller).
inline constexpr std::uint8_t kBulkInAddress = 0x81;
inline constexpr std::uint8_t kBulkOutAddress = 0x02;
inline constexpr std::uint16_t kFullSpeedMaxPacket = 64;
inline constexpr std::uint16_t kHighSpeedMaxPacket = 512;

// For development boards only: pid.codes' test VID:PID (hw/gadget/lightstage-gadget.sh).
// A product needs its own IDs.
inline constexpr std::uint16_t kDevelopmentVendorId = 0x1209;
inline constexpr std::uint16_t kDevelopmentProductId = 0x0001;

}  // namespace lightstage::hw::usb
