#include "backend_common.hpp"

#include <fmt/format.h>

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
