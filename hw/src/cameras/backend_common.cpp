#include "backend_common.hpp"

#include "lightstage/common/error.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <stdexcept>
#include <utility>

namespace lightstage::hw {

using camera::CameraError;

void note_adjusted(camera::Validation& v, std::string note) {
  if (v.status == camera::ConfigStatus::kValid) v.status = camera::ConfigStatus::kAdjusted;
  v.notes.push_back(std::move(note));
}

void note_invalid(camera::Validation& v, std::string note) {
  v.status = camera::ConfigStatus::kInvalid;
  v.notes.push_back(std::move(note));
}

std::string list_camera_uris(std::string_view scheme, const std::vector<std::string>& ids,
                             std::string_view none) {
  if (ids.empty()) return std::string(none);
  std::string text = "cameras: ";
  for (std::size_t i = 0; i < ids.size(); ++i) text += fmt::format("{}{}:{}", i ? ", " : "", scheme, ids[i]);
  return text;
}

double parse_positive(const camera::CameraUri& uri, const char* key, const std::string& text) {
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || !(value > 0)) {
    fail("camera URI '{}': option {}={} is not a positive number", uri.uri, key, text);
  }
  return value;
}

const camera::FormatInfo* find_offered_format(camera::Validation& v, camera::CameraConfig& config,
                                              const std::vector<camera::FormatInfo>& formats,
                                              const std::string& current) {
  if (config.pixel_format.empty()) config.pixel_format = current;
  for (const auto& f : formats) {
    if (f.pixel_format == config.pixel_format) return &f;
  }
  std::string names;
  for (const auto& f : formats) names += (names.empty() ? "" : ", ") + f.pixel_format;
  note_invalid(v, fmt::format("pixel_format '{}' is not one this camera delivers ({})", config.pixel_format,
                              names.empty() ? "none that Lightstage can unpack" : names));
  return nullptr;
}

camera::Size largest_size(const camera::FormatInfo& format) {
  camera::Size best;
  for (const auto& range : format.sizes) {
    if (static_cast<long>(range.max.width) * range.max.height > static_cast<long>(best.width) * best.height) {
      best = range.max;
    }
  }
  return best;
}

namespace {

// The size within `format`'s ranges, on their steps, nearest to `want`.
camera::Size nearest_size(const camera::FormatInfo& format, camera::Size want) {
  camera::Size best;
  long best_cost = -1;
  for (const auto& r : format.sizes) {
    auto snap = [](int v, int lo, int hi, int step) {
      v = std::clamp(v, lo, hi);
      return std::min(lo + (v - lo + step / 2) / step * step, hi);
    };
    const camera::Size s{snap(want.width, r.min.width, r.max.width, r.step_width),
                         snap(want.height, r.min.height, r.max.height, r.step_height)};
    const long cost = std::labs(s.width - want.width) + std::labs(s.height - want.height);
    if (best_cost < 0 || cost < best_cost) {
      best = s;
      best_cost = cost;
    }
  }
  return best;
}

}  // namespace

void snap_size(camera::Validation& v, camera::CameraConfig& config, const camera::FormatInfo& format,
               bool name_format) {
  if (config.size.width == 0 && config.size.height == 0) {
    config.size = largest_size(format);
    return;
  }
  const camera::Size nearest = nearest_size(format, config.size);
  if (nearest == config.size) return;
  note_adjusted(
      v, fmt::format("size {}x{} is not offered{}; nearest is {}x{}", config.size.width, config.size.height,
                     name_format ? " for " + config.pixel_format : "", nearest.width, nearest.height));
  config.size = nearest;
}

void clamp_roi(camera::Validation& v, std::optional<camera::Roi>& roi, camera::Size frame) {
  if (!roi) return;
  if (roi->width <= 0 || roi->height <= 0) {
    note_invalid(v, fmt::format("roi {}x{}+{}+{} is empty", roi->width, roi->height, roi->x, roi->y));
    return;
  }
  camera::Roi clamped = *roi;
  clamped.x = std::clamp(roi->x, 0, std::max(0, frame.width - 1));
  clamped.y = std::clamp(roi->y, 0, std::max(0, frame.height - 1));
  clamped.width = std::min(roi->width, frame.width - clamped.x);
  clamped.height = std::min(roi->height, frame.height - clamped.y);
  if (clamped == *roi) return;
  note_adjusted(v, fmt::format("roi {}x{}+{}+{} reaches outside the {}x{} frame; clamped to {}x{}+{}+{}",
                               roi->width, roi->height, roi->x, roi->y, frame.width, frame.height,
                               clamped.width, clamped.height, clamped.x, clamped.y));
  roi = clamped;
}

void clamp_buffer_count(camera::Validation& v, int& buffer_count, int lo, int hi) {
  if (buffer_count >= lo && buffer_count <= hi) return;
  const int clamped = std::clamp(buffer_count, lo, hi);
  note_adjusted(v,
                fmt::format("buffer_count {} is outside [{}, {}]; set to {}", buffer_count, lo, hi, clamped));
  buffer_count = clamped;
}

const camera::FormatInfo* validate_offered(camera::Validation& v, camera::CameraConfig& config,
                                           const std::vector<camera::FormatInfo>& formats,
                                           const std::string& current, bool name_format, int max_buffers) {
  const camera::FormatInfo* format = find_offered_format(v, config, formats, current);
  if (!format) return nullptr;
  snap_size(v, config, *format, name_format);
  clamp_roi(v, config.roi, config.size);
  clamp_buffer_count(v, config.buffer_count, 2, max_buffers);
  return format;
}

camera::CameraConfig require_configurable(const camera::Camera& camera, const camera::CameraConfig& requested,
                                          bool streaming, const std::string& uri) {
  if (streaming) throw CameraError(fmt::format("{}: cannot configure while streaming; stop() first", uri));
  camera::CameraConfig config = requested;
  require_valid(camera.validate(config), uri);
  return config;
}

void require_valid(const camera::Validation& v, const std::string& uri) {
  if (v.status == camera::ConfigStatus::kValid) return;
  throw CameraError(fmt::format("{}: configuration is {} ({}); call validate() and apply what it returns",
                                uri, camera::to_string(v.status), v.message()));
}

void check_software_trigger(const camera::CameraConfig& config, bool streaming, const std::string& uri) {
  if (config.trigger != camera::TriggerMode::kSoftware) {
    throw CameraError(CameraError::Kind::kUnsupported,
                      fmt::format("{}: trigger() needs trigger mode software (configured: {})", uri,
                                  camera::to_string(config.trigger)));
  }
  if (!streaming) throw CameraError(fmt::format("{}: trigger() before start()", uri));
}

void fill_frame_image(camera::Frame& frame, std::span<const std::uint8_t> data,
                      const camera::CameraConfig& config, std::size_t stride, const PixelFormatDesc& format,
                      const std::string& uri, std::uint64_t sequence) {
  try {
    frame.image =
        unpack_pixels(data, config.size.width, config.size.height, stride, format.packing, format.bit_depth);
  } catch (const std::invalid_argument& e) {
    throw CameraError(fmt::format("{}: frame {} is short: {}", uri, sequence, e.what()));
  }
  frame.pixel_format = config.pixel_format;
  frame.bit_depth = format.bit_depth;
  frame.cfa = format.cfa;
  if (config.roi) camera::crop_frame(frame, *config.roi, uri);
}

}  // namespace lightstage::hw
