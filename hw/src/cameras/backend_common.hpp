#pragma once
// What the V4L2 and libcamera backends do alike once a driver has handed
// over a buffer: the checks before a software trigger, and the conversion of
// the buffer into the frame's image; and how validate() records what it
// changed or refused. Everything device-specific (dequeuing,
// sequence and timestamp sources, requeuing) stays in the backends.

#include "lightstage/common/camera.hpp"
#include "lightstage/hw/pixel_formats.hpp"

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace lightstage::hw {

// Adds `note` to `v`: an adjustment turns a Valid result into Adjusted (an
// Invalid one stays Invalid); a refusal makes it Invalid.
void note_adjusted(camera::Validation& v, std::string note);
void note_invalid(camera::Validation& v, std::string note);

// Throws camera::CameraError (Unsupported) unless `config` asks for software
// triggering, and (Failed) when the camera is not `streaming`.
void check_software_trigger(const camera::CameraConfig& config, bool streaming, const std::string& uri);

// Unpacks `data` (rows of `stride` bytes in `format`) into frame.image at
// config.size, fills the frame's pixel format, bit depth and CFA, and crops
// to config.roi when set. A buffer too short for the image is a
// camera::CameraError naming `uri` and frame `sequence`.
void fill_frame_image(camera::Frame& frame, std::span<const std::uint8_t> data,
                      const camera::CameraConfig& config, std::size_t stride, const PixelFormatDesc& format,
                      const std::string& uri, std::uint64_t sequence);

}  // namespace lightstage::hw
