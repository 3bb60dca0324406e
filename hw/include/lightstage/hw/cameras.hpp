#pragma once
// Cameras by URI (common/camera.hpp is the interface):
//
//   v4l2:/dev/videoN[?options]   Video4Linux2 capture node, mmap streaming (v4l2_camera.hpp)
//   v4l2:N                       the same as v4l2:/dev/videoN
//   libcamera:ID                 a camera libcamera sees (`lightstage devices` lists the ids);
//   libcamera:                   the first one
//   aravis:DEVICE_ID[?options]   a GenICam camera (GigE Vision, USB3 Vision) through aravis 0.8;
//   aravis:                      the first one
//
// gphoto2:[MODEL|PORT] (DSLR and mirrorless cameras) is a camera::ShotSource,
// not a scheme here: hw/gphoto2_source.hpp opens it, the host wraps it into
// a camera. list_cameras() lists what open_camera() can open, so it leaves
// gphoto2 cameras to the scheme the host registers (probe_devices() lists
// them meanwhile).
//
// sim:PATH is registered by sim/ (lightstage-sim's virtual camera); hw/ does
// not know it. hw/docs/cameras.md tells how to bring a camera up on a board.

#include "lightstage/common/camera.hpp"

#include <memory>
#include <string>
#include <vector>

namespace lightstage::hw {

// Registers the v4l2:, libcamera: and aravis: schemes with common/camera.hpp's registry
// (a scheme whose library this build lacks is registered as unavailable, so
// asking for it says so). Idempotent and thread-safe.
void register_hw_cameras();

// register_hw_cameras(), then camera::open_camera_uri(uri).
std::unique_ptr<camera::Camera> open_camera(const std::string& uri);

// The cameras every registered scheme can see (enumeration failures are skipped).
std::vector<camera::CameraInfo> list_cameras();

// Each backend's part; defined in its own file, compiled only with its library.
camera::CameraScheme v4l2_camera_scheme();
camera::CameraScheme libcamera_camera_scheme();
camera::CameraScheme aravis_camera_scheme();

}  // namespace lightstage::hw
