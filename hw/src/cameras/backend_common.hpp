#pragma once
// What the V4L2, libcamera and aravis backends do alike: parsing numeric URI
// options; the steps of validate() that judge a config against what the camera
// offers, and how it records what it changed or refused; refusing an
// unvalidated config in configure(); the checks before a software trigger; and
// the conversion of a driver's buffer into the frame's image. Shared so that
// every backend treats a config, and words its notes, alike. Everything
// device-specific (dequeuing, sequence and timestamp sources, requeuing)
// stays in the backends.

#include "lightstage/common/camera.hpp"
#include "lightstage/hw/pixel_formats.hpp"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace lightstage::hw {

// Adds `note` to `v`: an adjustment turns a Valid result into Adjusted (an
// Invalid one stays Invalid); a refusal makes it Invalid.
void note_adjusted(camera::Validation& v, std::string note);
void note_invalid(camera::Validation& v, std::string note);

// "cameras: SCHEME:ID, ..." for the message of a camera that cannot be
// found, so that it names the URIs that would work; `none` when `ids` is empty.
std::string list_camera_uris(std::string_view scheme, const std::vector<std::string>& ids,
                             std::string_view none);

// URI option `key`'s `text` as a number > 0; anything else is an InputError
// naming the URI.
double parse_positive(const camera::CameraUri& uri, const char* key, const std::string& text);

// validate() steps. Each one adjusts `config` in place and notes in `v` what it
// changed or refused.

// The entry of `formats` named config.pixel_format (set to `current` when
// empty); nullptr, noting the formats the camera does deliver, when none is.
const camera::FormatInfo* find_offered_format(camera::Validation& v, camera::CameraConfig& config,
                                              const std::vector<camera::FormatInfo>& formats,
                                              const std::string& current);

// The largest size `format` offers (by area).
camera::Size largest_size(const camera::FormatInfo& format);

// Sets config.size to the offered size of `format` nearest to it (0x0: the
// largest). `name_format`: the note names the pixel format, for cameras whose
// sizes depend on it.
void snap_size(camera::Validation& v, camera::CameraConfig& config, const camera::FormatInfo& format,
               bool name_format);

// Refuses an empty `roi`; clamps one that reaches outside a `frame`-sized image.
void clamp_roi(camera::Validation& v, std::optional<camera::Roi>& roi, camera::Size frame);

// Clamps `buffer_count` to [lo, hi].
void clamp_buffer_count(camera::Validation& v, int& buffer_count, int lo, int hi);

// The steps of validate() for a camera whose formats list their sizes: the
// offered format (find_offered_format), its nearest size (snap_size), the ROI
// and the buffer count in [2, max_buffers]. nullptr when the format is not offered.
const camera::FormatInfo* validate_offered(camera::Validation& v, camera::CameraConfig& config,
                                           const std::vector<camera::FormatInfo>& formats,
                                           const std::string& current, bool name_format, int max_buffers);

// Throws camera::CameraError naming `uri` and validate()'s notes unless `v` is
// Valid: configure() applies only what validate() accepts unchanged.
void require_valid(const camera::Validation& v, const std::string& uri);

// configure()'s first steps: refuses while `streaming`, and a config that
// `camera`.validate() would change (require_valid). Returns the config.
camera::CameraConfig require_configurable(const camera::Camera& camera, const camera::CameraConfig& requested,
                                          bool streaming, const std::string& uri);

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
