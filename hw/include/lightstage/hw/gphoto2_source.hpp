#pragma once
// DSLR and mirrorless cameras over USB through libgphoto2 (2.5.30 in Debian
// 12), as a camera::ShotSource (common/shot_source.hpp): settings through the
// camera's configuration widgets, shots fired with a capture command or by
// the remote-release port while tethered, files downloaded as they appear.
//
//   gphoto2:                     the first camera libgphoto2 detects
//   gphoto2:MODEL                the camera of that model ("Canon EOS 5D Mark IV")
//   gphoto2:PORT                 the camera on that port ("usb:001,004"; anything with a ':')
//   ...?download=DIR             download into DIR instead of the folder the caller gives
//   ...?model=MODEL              with a PORT: the driver to use when autodetection
//                                does not list the port (e.g. ptpip:192.168.1.10, or
//                                libgphoto2's "Directory Browse" on a disk:PATH port)
//
// Not a camera::Camera scheme: the host wraps a ShotSource into one
// (host/capture/file_camera.hpp). hw/docs/cameras.md tells how to bring a
// camera up (the desktop's auto-mounter, permissions, camera settings).
//
// Built only with libgphoto2; without it both functions throw
// camera::CameraError (kUnsupported) saying so.

#include "lightstage/common/shot_source.hpp"

#include <filesystem>
#include <memory>
#include <vector>

namespace lightstage::hw {

// The cameras libgphoto2 detects: uri "gphoto2:MODEL", or "gphoto2:PORT" for
// each of two or more cameras of one model; driver "libgphoto2 PORT". Empty
// (never an error) when there is none.
std::vector<camera::CameraInfo> list_gphoto2_cameras();

// Opens the camera `uri` names and sets it to keep its shots on the memory
// card (see the source for why). Files are downloaded into `download_dir`
// (or the URI's download=DIR), which must exist and be writable. Throws
// camera::CameraError naming the URI: kNotFound (listing the cameras seen),
// kBusy (another program holds the camera; the message says how to free it),
// kFailed otherwise; InputError for a malformed URI.
std::unique_ptr<camera::ShotSource> open_gphoto2_source(const camera::CameraUri& uri,
                                                        const std::filesystem::path& download_dir);

}  // namespace lightstage::hw
