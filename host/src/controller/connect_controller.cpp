#include "lightstage/common/socket_link.hpp"
#include "lightstage/host/controller/controller_client.hpp"

namespace lightstage {

std::unique_ptr<ControllerClient> connect_controller(const std::string& uri,
                                                     ControllerClientOptions options) {
  return std::make_unique<ControllerClient>(connect_socket_link(uri, std::chrono::milliseconds(2000)),
                                            std::move(options));
}

}  // namespace lightstage
