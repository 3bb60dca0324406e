#pragma once
// libcamera allows one CameraManager per process: every user in hw/ (the
// camera backend, `lightstage devices`) shares this one. It is started on
// first use and stopped when the last holder lets go.

#include <libcamera/camera_manager.h>

#include <memory>
#include <string>
#include <vector>

namespace lightstage::hw {

// Throws camera::CameraError when the manager cannot start.
std::shared_ptr<libcamera::CameraManager> shared_camera_manager();

// The ids of the cameras libcamera sees.
std::vector<std::string> libcamera_camera_ids(const libcamera::CameraManager& manager);

}  // namespace lightstage::hw
