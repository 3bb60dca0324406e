#include "lightstage/host/controller/controller_client.hpp"
#include "lightstage/hw/links.hpp"

namespace lightstage {

std::unique_ptr<ControllerClient> connect_controller(const std::string& uri,
                                                     ControllerClientOptions options) {
  // A controller that is just starting (or a USB gadget being enumerated) gets a moment to appear.
  return std::make_unique<ControllerClient>(hw::connect_link(uri, std::chrono::milliseconds(2000)),
                                            std::move(options));
}

}  // namespace lightstage
