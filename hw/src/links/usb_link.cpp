// usb: links through libusb's synchronous bulk transfers. Reads and writes
// run in slices of at most kSlice, so shutdown() from another thread takes
// effect within one slice, and a libusb timeout of 0 (= forever) never occurs.
#include "lightstage/hw/usb_link.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/hw/usb_interface.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <libusb.h>

#include <algorithm>
#include <atomic>
#include <mutex>
#include <thread>
#include <vector>

namespace lightstage::hw {

using namespace std::chrono_literals;

namespace {

constexpr auto kSlice = 100ms;
// A controller that takes no data for this long is gone (or wedged): fail the write.
constexpr auto kWriteTimeout = 5s;
// Stale bytes a controller queued for a previous host session are drained on open.
constexpr auto kDrainQuiet = 20ms;
constexpr int kMaxDrainPackets = 256;
constexpr std::size_t kWriteChunk = 16 * 1024;

std::string usb_error(int code) {
  return fmt::format("{} ({})", libusb_error_name(code), libusb_strerror(code));
}

struct Endpoints {
  int interface_number = -1;
  std::uint8_t in = 0;
  std::uint8_t out = 0;
  int in_max_packet = 0;
  int out_max_packet = 0;
};

// The controller interface: ours by class/subclass/protocol, else the first
// vendor-specific interface with a bulk IN and a bulk OUT endpoint.
std::optional<Endpoints> find_endpoints(libusb_device* device) {
  libusb_config_descriptor* config = nullptr;
  if (libusb_get_active_config_descriptor(device, &config) != 0) return std::nullopt;
  std::optional<Endpoints> ours;
  std::optional<Endpoints> fallback;
  for (int i = 0; i < config->bNumInterfaces; ++i) {
    const libusb_interface& interface = config->interface[i];
    for (int a = 0; a < interface.num_altsetting; ++a) {
      const libusb_interface_descriptor& alt = interface.altsetting[a];
      if (alt.bInterfaceClass != usb::kInterfaceClass || alt.bAlternateSetting != 0) continue;
      Endpoints found;
      found.interface_number = alt.bInterfaceNumber;
      for (int e = 0; e < alt.bNumEndpoints; ++e) {
        const libusb_endpoint_descriptor& endpoint = alt.endpoint[e];
        if ((endpoint.bmAttributes & LIBUSB_TRANSFER_TYPE_MASK) != LIBUSB_TRANSFER_TYPE_BULK) continue;
        const int max_packet = std::max<int>(1, endpoint.wMaxPacketSize & 0x7ff);
        if ((endpoint.bEndpointAddress & LIBUSB_ENDPOINT_DIR_MASK) == LIBUSB_ENDPOINT_IN && found.in == 0) {
          found.in = endpoint.bEndpointAddress;
          found.in_max_packet = max_packet;
        } else if ((endpoint.bEndpointAddress & LIBUSB_ENDPOINT_DIR_MASK) == LIBUSB_ENDPOINT_OUT &&
                   found.out == 0) {
          found.out = endpoint.bEndpointAddress;
          found.out_max_packet = max_packet;
        }
      }
      if (found.in == 0 || found.out == 0) continue;
      if (alt.bInterfaceSubClass == usb::kInterfaceSubclass &&
          alt.bInterfaceProtocol == usb::kInterfaceProtocol) {
        if (!ours) ours = found;
      } else if (!fallback) {
        fallback = found;
      }
    }
  }
  libusb_free_config_descriptor(config);
  return ours ? ours : fallback;
}

std::string serial_of(libusb_device_handle* handle, const libusb_device_descriptor& descriptor) {
  if (descriptor.iSerialNumber == 0) return {};
  unsigned char text[256] = {};
  const int n = libusb_get_string_descriptor_ascii(handle, descriptor.iSerialNumber, text, sizeof text);
  return n > 0 ? std::string(reinterpret_cast<const char*>(text), static_cast<std::size_t>(n))
               : std::string();
}

struct DeviceList {
  libusb_device** devices = nullptr;
  ssize_t count = 0;
  explicit DeviceList(libusb_context* context) {
    count = libusb_get_device_list(context, &devices);
    if (count < 0)
      throw LinkClosed(fmt::format("usb: cannot list USB devices: {}", usb_error(static_cast<int>(count))));
  }
  ~DeviceList() { libusb_free_device_list(devices, 1); }
  DeviceList(const DeviceList&) = delete;
  DeviceList& operator=(const DeviceList&) = delete;
};

// The outcome of one look for the device.
struct Search {
  libusb_device_handle* handle = nullptr;  // opened, when found
  std::vector<std::string> serials_seen;   // of VID:PID devices that did not match
  std::string problem;                     // a device was there but could not be opened
};

Search find_device(libusb_context* context, const UsbDeviceId& id) {
  Search search;
  const DeviceList list(context);
  for (ssize_t i = 0; i < list.count; ++i) {
    libusb_device* device = list.devices[i];
    libusb_device_descriptor descriptor{};
    if (libusb_get_device_descriptor(device, &descriptor) != 0) continue;
    if (descriptor.idVendor != id.vendor_id || descriptor.idProduct != id.product_id) continue;
    libusb_device_handle* handle = nullptr;
    if (const int rc = libusb_open(device, &handle); rc != 0) {
      search.problem = fmt::format(
          "cannot open bus {} device {}: {}{}", libusb_get_bus_number(device),
          libusb_get_device_address(device), usb_error(rc),
          rc == LIBUSB_ERROR_ACCESS ? " (install hw/udev/70-lightstage.rules, see hw/docs/links.md)" : "");
      continue;
    }
    if (id.serial) {
      const std::string serial = serial_of(handle, descriptor);
      if (serial != *id.serial) {
        search.serials_seen.push_back(serial.empty() ? "(none)" : serial);
        libusb_close(handle);
        continue;
      }
    }
    search.handle = handle;
    return search;
  }
  return search;
}

class UsbLink final : public ByteLink {
 public:
  UsbLink(std::unique_ptr<UsbContext> context, std::unique_ptr<UsbHotplugWatch> watch,
          libusb_device_handle* handle, Endpoints endpoints, std::string description)
      : context_(std::move(context)),
        watch_(std::move(watch)),
        handle_(handle),
        endpoints_(endpoints),
        packet_(static_cast<std::size_t>(endpoints.in_max_packet)),
        description_(std::move(description)) {}

  ~UsbLink() override {
    libusb_release_interface(handle_, endpoints_.interface_number);
    libusb_close(handle_);
    watch_.reset();  // before the context it belongs to
  }
  UsbLink(const UsbLink&) = delete;
  UsbLink& operator=(const UsbLink&) = delete;

  // Reads whole packets (wMaxPacketSize) so a transfer always ends at a packet
  // boundary: no overflow, and no wait for a zero-length packet after a
  // message that fills its last packet exactly.
  std::size_t read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) override {
    const std::lock_guard lock(read_mutex_);
    if (pending_begin_ < pending_.size()) return take_pending(buffer);
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      check_open();
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      const auto slice = std::clamp<std::chrono::milliseconds>(left, 1ms, kSlice);
      int transferred = 0;
      const int rc =
          libusb_bulk_transfer(handle_, endpoints_.in, packet_.data(), static_cast<int>(packet_.size()),
                               &transferred, static_cast<unsigned>(slice.count()));
      if (transferred > 0) {  // also after a timeout: data may have arrived before it
        pending_.assign(packet_.begin(), packet_.begin() + transferred);
        pending_begin_ = 0;
        return take_pending(buffer);
      }
      if (rc != 0 && rc != LIBUSB_ERROR_TIMEOUT && rc != LIBUSB_ERROR_INTERRUPTED) fail_transfer("read", rc);
      if (std::chrono::steady_clock::now() >= deadline) return 0;
    }
  }

  void write(std::span<const std::uint8_t> bytes) override {
    const std::lock_guard lock(write_mutex_);
    std::size_t done = 0;
    while (done < bytes.size()) {
      const std::size_t chunk = std::min(kWriteChunk, bytes.size() - done);
      done += send(bytes.subspan(done, chunk));
    }
    // The controller reads in large requests that end at a short packet: a
    // message filling its last packet exactly needs a zero-length packet after it.
    if (!bytes.empty() && bytes.size() % static_cast<std::size_t>(endpoints_.out_max_packet) == 0) send({});
  }

  void shutdown() override { closed_ = true; }

  std::string describe() const override { return description_; }

  // Drops what the controller queued for an earlier host session.
  void drain_stale_input() {
    std::uint8_t scratch[512];
    for (int i = 0; i < kMaxDrainPackets &&
                    read(scratch, std::chrono::duration_cast<std::chrono::milliseconds>(kDrainQuiet)) > 0;
         ++i) {
    }
  }

 private:
  std::size_t take_pending(std::span<std::uint8_t> buffer) {
    const std::size_t n = std::min(buffer.size(), pending_.size() - pending_begin_);
    std::copy_n(pending_.begin() + static_cast<std::ptrdiff_t>(pending_begin_), n, buffer.begin());
    pending_begin_ += n;
    return n;
  }

  void check_open() {
    if (closed_) throw LinkClosed(fmt::format("{}: link closed", description_));
    if (watch_->registered() && watch_->poll(0ms).left > 0 && device_gone()) {
      throw LinkClosed(fmt::format("{}: the device was unplugged", description_));
    }
  }

  // A hotplug "left" event may be another device of the same VID:PID: is ours still listed?
  bool device_gone() {
    const DeviceList list(context_->get());
    libusb_device* ours = libusb_get_device(handle_);
    return std::none_of(list.devices, list.devices + list.count,
                        [ours](libusb_device* d) { return d == ours; });
  }

  [[noreturn]] void fail_transfer(const char* what, int rc) {
    if (rc == LIBUSB_ERROR_NO_DEVICE)
      throw LinkClosed(fmt::format("{}: the device was unplugged", description_));
    throw LinkClosed(fmt::format("{}: bulk {} failed: {}", description_, what, usb_error(rc)));
  }

  // Sends one chunk (or a zero-length packet); returns its size.
  std::size_t send(std::span<const std::uint8_t> chunk) {
    auto deadline = std::chrono::steady_clock::now() + kWriteTimeout;  // moved on by every progress
    std::size_t done = 0;
    do {
      check_open();
      int transferred = 0;
      // libusb takes a non-const buffer for both directions; OUT transfers only read it.
      auto* data = const_cast<std::uint8_t*>(chunk.data() + done);
      const int rc = libusb_bulk_transfer(handle_, endpoints_.out, chunk.empty() ? nullptr : data,
                                          static_cast<int>(chunk.size() - done), &transferred,
                                          static_cast<unsigned>(kSlice.count()));
      if (transferred > 0) {
        done += static_cast<std::size_t>(transferred);
        deadline = std::chrono::steady_clock::now() + kWriteTimeout;
      }
      if (rc == 0 && done == chunk.size()) return done;
      if (rc != 0 && rc != LIBUSB_ERROR_TIMEOUT && rc != LIBUSB_ERROR_INTERRUPTED) fail_transfer("write", rc);
    } while (std::chrono::steady_clock::now() < deadline);
    throw LinkClosed(fmt::format("{}: the controller took no data for {} s", description_,
                                 std::chrono::duration_cast<std::chrono::seconds>(kWriteTimeout).count()));
  }

  std::unique_ptr<UsbContext> context_;
  std::unique_ptr<UsbHotplugWatch> watch_;
  libusb_device_handle* handle_;
  Endpoints endpoints_;
  std::vector<std::uint8_t> packet_;
  std::vector<std::uint8_t> pending_;
  std::size_t pending_begin_ = 0;
  std::mutex read_mutex_;
  std::mutex write_mutex_;
  std::atomic<bool> closed_{false};
  std::string description_;
};

// Claims the interface on an opened handle; closes the handle and throws on failure.
Endpoints claim(libusb_device_handle* handle, const std::string& uri) {
  const auto endpoints = find_endpoints(libusb_get_device(handle));
  std::string problem;
  if (!endpoints) {
    problem =
        "the device has no vendor interface with bulk IN and OUT endpoints (is it a Lightstage controller?)";
  } else {
    // Let libusb detach a kernel driver bound to the interface (and reattach it
    // on release), where the platform supports it.
    if (libusb_has_capability(LIBUSB_CAP_SUPPORTS_DETACH_KERNEL_DRIVER))
      libusb_set_auto_detach_kernel_driver(handle, 1);
    if (const int rc = libusb_claim_interface(handle, endpoints->interface_number); rc != 0) {
      problem = fmt::format("cannot claim interface {}: {}{}", endpoints->interface_number, usb_error(rc),
                            rc == LIBUSB_ERROR_BUSY ? " (another program has it open)" : "");
    }
  }
  if (!problem.empty()) {
    libusb_close(handle);
    throw LinkClosed(fmt::format("{}: {}", uri, problem));
  }
  return *endpoints;
}

}  // namespace

// ---- UsbContext -----------------------------------------------------------

UsbContext::UsbContext() {
  if (const int rc = libusb_init(&context_); rc != 0) {
    context_ = nullptr;
    throw Error(fmt::format("usb: libusb_init failed: {}", usb_error(rc)));
  }
}

UsbContext::~UsbContext() {
  if (context_) libusb_exit(context_);
}

bool UsbContext::has_hotplug() { return libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG) != 0; }

// ---- UsbHotplugWatch ------------------------------------------------------

struct UsbHotplugCallback {
  static int on_event(libusb_context*, libusb_device*, libusb_hotplug_event event, void* user_data) {
    auto* watch = static_cast<UsbHotplugWatch*>(user_data);
    if (event == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED) ++watch->arrived_;
    if (event == LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT) ++watch->left_;
    return 0;  // stay registered
  }
};

UsbHotplugWatch::UsbHotplugWatch(UsbContext& context, std::uint16_t vendor_id, std::uint16_t product_id)
    : context_(context) {
  if (!UsbContext::has_hotplug()) return;
  libusb_hotplug_callback_handle handle = 0;
  const int rc = libusb_hotplug_register_callback(
      context_.get(),
      static_cast<libusb_hotplug_event>(LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED |
                                        LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT),
      static_cast<libusb_hotplug_flag>(0), vendor_id == 0 ? LIBUSB_HOTPLUG_MATCH_ANY : vendor_id,
      product_id == 0 ? LIBUSB_HOTPLUG_MATCH_ANY : product_id, LIBUSB_HOTPLUG_MATCH_ANY,
      &UsbHotplugCallback::on_event, this, &handle);
  if (rc != 0) {
    throw Error(fmt::format("usb:{:04x}:{:04x}: cannot register for hotplug events: {}", vendor_id,
                            product_id, usb_error(rc)));
  }
  handle_ = handle;
  registered_ = true;
}

UsbHotplugWatch::~UsbHotplugWatch() {
  if (registered_) libusb_hotplug_deregister_callback(context_.get(), handle_);
}

UsbHotplugWatch::Events UsbHotplugWatch::poll(std::chrono::milliseconds timeout) {
  if (!registered_) {
    std::this_thread::sleep_for(timeout);
  } else {
    timeval tv{};
    tv.tv_sec = static_cast<time_t>(timeout.count() / 1000);
    tv.tv_usec = static_cast<suseconds_t>((timeout.count() % 1000) * 1000);
    libusb_handle_events_timeout_completed(context_.get(), &tv, nullptr);
  }
  return Events{arrived_.exchange(0), left_.exchange(0)};
}

// ---- connect_usb_link -----------------------------------------------------

std::unique_ptr<ByteLink> connect_usb_link(const std::string& uri, std::chrono::milliseconds timeout) {
  const UsbDeviceId id = parse_usb_uri(uri);
  auto context = std::make_unique<UsbContext>();
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  auto arrivals = std::make_unique<UsbHotplugWatch>(*context, id.vendor_id, id.product_id);
  Search search = find_device(context->get(), id);
  // Wait for the device to appear: on a hotplug event where libusb has them,
  // else by enumerating again now and then.
  while (!search.handle && std::chrono::steady_clock::now() < deadline) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    const auto events = arrivals->poll(std::clamp<std::chrono::milliseconds>(left, 0ms, 200ms));
    if (events.arrived > 0 || !arrivals->registered()) search = find_device(context->get(), id);
  }
  if (!search.handle) {
    const std::string ids = fmt::format("{:04x}:{:04x}", id.vendor_id, id.product_id);
    if (!search.problem.empty()) throw LinkClosed(fmt::format("{}: {}", uri, search.problem));
    if (!search.serials_seen.empty()) {
      throw LinkClosed(fmt::format("{}: no USB device {} with serial '{}' (found serials: {})", uri, ids,
                                   *id.serial, fmt::join(search.serials_seen, ", ")));
    }
    throw LinkClosed(
        fmt::format("{}: no such device: nothing with VID:PID {} is plugged in "
                    "(`lightstage devices` lists what libusb sees)",
                    uri, ids));
  }
  const Endpoints endpoints = claim(search.handle, uri);
  auto link = std::make_unique<UsbLink>(std::move(context), std::move(arrivals), search.handle, endpoints,
                                        fmt::format("{} (interface {}, bulk IN 0x{:02x}, OUT 0x{:02x})", uri,
                                                    endpoints.interface_number, endpoints.in, endpoints.out));
  link->drain_stale_input();
  return link;
}

}  // namespace lightstage::hw
