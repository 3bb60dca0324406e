#pragma once
// Cameras whose shots arrive as files: a DSLR or mirrorless camera fired
// through its remote-release port (the controller's focus and shutter lines)
// or over USB (gphoto2), its RAW files downloaded by tethering or written by a
// tethering program into a folder. A ShotSource only says which files are new
// and sets what the camera lets it set; the host decodes each file into a
// camera::Frame (host/capture/file_camera.hpp), so hw/ needs no RAW decoder.
//
//   gphoto2:[MODEL|PORT]   a camera libgphoto2 sees (hw/, hw/gphoto2_source.hpp)
//   folder:PATH            files appearing in PATH (host/)

#include "lightstage/common/camera.hpp"

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace lightstage::camera {

// What a stills camera is set to. Unset fields: leave as they are (apply) or
// not known (read back).
struct ShotSettings {
  std::optional<double> exposure_us;        // shutter speed
  std::optional<double> iso;                // ISO speed
  std::optional<double> f_number;           // aperture
  std::optional<std::string> image_format;  // the camera's own name for it, e.g. "RAW"
};

struct ArrivedFile {
  std::filesystem::path path;   // complete (never half written) and readable
  std::int64_t arrived_ns = 0;  // CLOCK_MONOTONIC when the source saw it complete
};

class ShotSource {
 public:
  virtual ~ShotSource() = default;
  ShotSource(const ShotSource&) = delete;
  ShotSource& operator=(const ShotSource&) = delete;

  const std::string& uri() const { return uri_; }
  virtual CameraInfo info() const = 0;

  // True when trigger() can fire the camera; false when only its remote port can.
  virtual bool software_trigger() const = 0;

  // Sets what the camera lets the source set (each to the nearest value the
  // camera offers) and returns what the camera reports it now uses. Throws
  // CameraError (kUnsupported) naming a setting the camera lacks or a value
  // it cannot come near, with the choices it offers.
  virtual ShotSettings apply(const ShotSettings& wanted) = 0;

  // Starts watching for files; files that were there before are never reported.
  virtual void start() = 0;
  virtual void stop() = 0;  // idempotent

  // Fires one shot (software_trigger() only; CameraError otherwise). Its file
  // is reported by wait_file() like any other.
  virtual void trigger() = 0;

  // The next new file, in the order the camera took them, or nullopt when none
  // arrives within `timeout`. Throws CameraError when the camera fails or goes
  // away (Kind::kDisconnected), its card is full, or it is in the wrong mode.
  virtual std::optional<ArrivedFile> wait_file(std::chrono::milliseconds timeout) = 0;

 protected:
  explicit ShotSource(std::string uri) : uri_(std::move(uri)) {}

 private:
  std::string uri_;
};

}  // namespace lightstage::camera
