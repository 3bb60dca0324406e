#pragma once
// Stills cameras as camera::Camera: a ShotSource's files (common/shot_source.hpp)
// decoded into frames, so a DSLR captures like any other camera.
//
//   folder:PATH[?poll_ms=N]         files a tethering program (or the simulated
//                                   DSLR) writes into PATH; fired by the rig's
//                                   trigger (the camera's remote port)
//   gphoto2:[MODEL|PORT][?download=DIR&fire=usb|remote&aperture=F&iso=N&format=NAME]
//                                   a camera libgphoto2 sees (hw/gphoto2_source.hpp),
//                                   fired over USB (default) or by the rig's
//                                   trigger on its remote port; shots
//                                   downloaded into DIR (default
//                                   ./lightstage-shots), never overwriting;
//                                   aperture, ISO and image format (e.g.
//                                   RAW) set as capturing starts
//   Both take demosaic=half|full for RAW files.
//
// Each file is decoded (io/raw_image.hpp: RAW linear, at half size by
// default or `?demosaic=full`; TIFF; JPEG/PNG as they are, 8-bit and not
// linear: give `capture --response` for those) into a frame, grey or BGR.
// Every file of a capture must be of one kind and size (a camera set to
// RAW + JPEG is refused: two files per shot). Its EXIF gives the frame's exposure and ISO (analogue gain =
// ISO / 100) and its time (DateTimeOriginal + SubSec, on the camera's own
// clock: Frame::own_clock; shot_matcher.hpp matches such frames to steps).
// A file that does not decode is skipped with a warning: its step is retaken.
//
// Exposure: a camera that the source can set (gphoto2) is set to the nearest
// shutter speed it offers. A folder's camera is set by hand: set_controls
// records the exposure asked. Either way a frame carries the exposure its
// EXIF gives, and the capture refuses a shot more than a sixth of a stop away
// from what its step asked (capture_runner.hpp).

#include "lightstage/common/shot_source.hpp"
#include "lightstage/host/io/raw_image.hpp"

#include <memory>

namespace lightstage {

struct FileCameraOptions {
  io::RawDemosaic demosaic = io::RawDemosaic::half;
  // Fired by the rig's trigger on the camera's remote port (hardware trigger)
  // rather than by the source (software trigger).
  bool remote_port = true;
  // Set when capturing starts (gphoto2: URI options aperture=F, iso=N, format=NAME).
  camera::ShotSettings settings;
};

std::unique_ptr<camera::Camera> make_file_camera(std::unique_ptr<camera::ShotSource> source,
                                                 FileCameraOptions options = {});

// Registers folder: and gphoto2: with common/camera.hpp's registry (gphoto2:
// as unavailable when this build has no libgphoto2). Idempotent.
void register_file_cameras();

}  // namespace lightstage
