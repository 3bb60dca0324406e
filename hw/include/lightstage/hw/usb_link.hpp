#pragma once
// usb:VID:PID[:SERIAL] — the host's link to a controller board acting as a USB
// FunctionFS gadget (ffs_link.hpp): the vendor interface of usb_interface.hpp,
// its bulk IN and OUT endpoints driven through libusb.
//
// parse_usb_uri() is always built; the rest needs libusb (backend_built("usb")).

#include "lightstage/common/link.hpp"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

struct libusb_context;

namespace lightstage::hw {

struct UsbDeviceId {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::optional<std::string> serial;  // iSerialNumber; any device of VID:PID when absent

  std::string uri() const;  // "usb:1209:0001[:SERIAL]"
};

// VID and PID are 1-4 hex digits; the serial is the rest of the URI, verbatim.
// Throws InputError naming the URI and what is wrong.
UsbDeviceId parse_usb_uri(const std::string& uri);

// A libusb context (libusb_init). Throws Error when libusb cannot start.
class UsbContext {
 public:
  UsbContext();
  ~UsbContext();
  UsbContext(const UsbContext&) = delete;
  UsbContext& operator=(const UsbContext&) = delete;

  libusb_context* get() const { return context_; }
  // Whether libusb reports device arrival and removal on this platform.
  static bool has_hotplug();

 private:
  libusb_context* context_ = nullptr;
};

// Watches one VID:PID for arrival and removal through libusb's hotplug
// callbacks. Without hotplug support registered() is false and poll() only waits.
class UsbHotplugWatch {
 public:
  struct Events {
    int arrived = 0;
    int left = 0;
  };

  UsbHotplugWatch(UsbContext& context, std::uint16_t vendor_id, std::uint16_t product_id);
  ~UsbHotplugWatch();
  UsbHotplugWatch(const UsbHotplugWatch&) = delete;
  UsbHotplugWatch& operator=(const UsbHotplugWatch&) = delete;

  bool registered() const { return registered_; }
  // Handles libusb events for up to `timeout`; returns what happened since the last call.
  Events poll(std::chrono::milliseconds timeout);

 private:
  UsbContext& context_;
  bool registered_ = false;
  int handle_ = 0;
  // Counted by the callback in whichever thread runs libusb's event handling.
  std::atomic<int> arrived_{0};
  std::atomic<int> left_{0};
  friend struct UsbHotplugCallback;
};

// Opens the device and claims the controller interface (detaching a kernel
// driver if one holds it), waiting up to `timeout` for the device to appear.
// Throws InputError for a malformed URI, LinkClosed naming VID:PID (and serial)
// when no such device is present or it cannot be opened (with the remedy: udev
// rule, another program holding it). The link throws LinkClosed when the device goes away.
std::unique_ptr<ByteLink> connect_usb_link(const std::string& uri,
                                           std::chrono::milliseconds timeout = std::chrono::milliseconds(0));

}  // namespace lightstage::hw
