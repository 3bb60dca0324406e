#include "lightstage/hw/links.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/serial_link.hpp"
#include "lightstage/common/socket_link.hpp"
#include "lightstage/hw/backends.hpp"
#include "lightstage/hw/ffs_link.hpp"
#include "lightstage/hw/usb_link.hpp"

#include <fmt/format.h>

namespace lightstage::hw {
namespace {

std::string scheme_of(const std::string& uri) {
  const std::size_t colon = uri.find(':');
  return colon == std::string::npos ? std::string() : uri.substr(0, colon);
}

std::string list_schemes(bool for_listen) {
  std::string list;
  for (const auto& scheme : link_schemes()) {
    if (!(for_listen ? scheme.listen : scheme.connect)) continue;
    list += (list.empty() ? "" : ", ") + scheme.form;
    if (!scheme.built) list += " (not in this build)";
  }
  return list;
}

const LinkScheme& find_scheme(const std::string& uri, bool for_listen) {
  const std::string name = scheme_of(uri);
  const char* verb = for_listen ? "listen on" : "connect to";
  for (const auto& scheme : link_schemes()) {
    if (scheme.scheme != name) continue;
    if (!(for_listen ? scheme.listen : scheme.connect)) {
      fail("'{}': cannot {} a {}: link ({}; use one of: {})", uri, verb, name,
           name == "usb"   ? "usb: is the host's side, the controller listens on ffs:"
           : name == "ffs" ? "ffs: is the controller's side, the host connects with usb:"
                           : "not supported",
           list_schemes(for_listen));
    }
    if (!scheme.built) {
      throw Error(fmt::format("'{}': this build has no {}: links (built without {}); available: {}", uri,
                              name, scheme.missing, list_schemes(for_listen)));
    }
    return scheme;
  }
  if (name.empty()) fail("'{}' is not a link URI (expected one of: {})", uri, list_schemes(for_listen));
  fail("'{}': unknown link scheme '{}' (expected one of: {})", uri, name, list_schemes(for_listen));
}

std::unique_ptr<ByteLink> connect_serial(const std::string& uri, std::chrono::milliseconds timeout) {
  if (timeout.count() > 0) {
    // The listener waits for a device that is not there yet (a board still booting).
    if (auto link = listen_serial_link(uri)->accept(timeout)) return link;
  }
  return open_serial_link(uri);  // opens, or says precisely why not
}

}  // namespace

const std::vector<LinkScheme>& link_schemes() {
  static const std::vector<LinkScheme> schemes = {
      {"tcp", "tcp:HOST:PORT", true, true, true, {}},
      {"unix", "unix:PATH", true, true, true, {}},
      {"serial", "serial:DEVICE[,BAUD][,rtscts]", true, true, true, {}},
      {"usb", "usb:VID:PID[:SERIAL]", true, false, backend_built("usb"), "libusb-1.0 (libusb-1.0-0-dev)"},
      {"ffs", "ffs:MOUNT", false, true, true, {}},
  };
  return schemes;
}

std::unique_ptr<ByteLink> connect_link(const std::string& uri, std::chrono::milliseconds timeout) {
  const std::string scheme = find_scheme(uri, false).scheme;
  if (scheme == "tcp" || scheme == "unix") return connect_socket_link(uri, timeout);
  if (scheme == "serial") return connect_serial(uri, timeout);
#ifdef LIGHTSTAGE_HAVE_LIBUSB
  if (scheme == "usb") return connect_usb_link(uri, timeout);
#endif
  throw Error(
      fmt::format("'{}': no connector for scheme '{}'", uri, scheme));  // a scheme listed but not wired
}

std::unique_ptr<LinkListener> listen_link(const std::string& uri) {
  const std::string scheme = find_scheme(uri, true).scheme;
  if (scheme == "tcp" || scheme == "unix") return listen_socket_link(uri);
  if (scheme == "serial") return listen_serial_link(uri);
  if (scheme == "ffs") return listen_ffs_link(uri);
  throw Error(fmt::format("'{}': no listener for scheme '{}'", uri, scheme));
}

}  // namespace lightstage::hw
