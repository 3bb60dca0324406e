#pragma once
// The host's `sim:PATH` camera: lightstage-sim's virtual camera (camera_service.hpp)
// behind the common camera interface, so capture code cannot tell it from a
// real one.

#include "lightstage/common/camera.hpp"

#include <memory>
#include <string>

namespace lightstage::sim {

// Connects to the virtual camera at the Unix socket `socket_path`. Throws
// camera::CameraError (NotFound) naming it when nobody serves there.
std::unique_ptr<::lightstage::camera::Camera> open_sim_camera(const std::string& socket_path);

// Registers the "sim" camera scheme (sim:PATH) with camera::open_camera_uri.
void register_sim_camera();

}  // namespace lightstage::sim
