#include "lightstage/host/report/light_statistics.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/simd_clones.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>

namespace lightstage::report {
namespace {

constexpr double kDefaultShadowThreshold = 0.02;

LightStatistics frame_statistics(const Frame& frame) {
  LightStatistics s;
  s.file = frame.filename;
  s.led_id = frame.led_id;
  s.direction = frame.light_direction;
  s.exposure_us = frame.exposure_us;
  s.gain = frame.gain;
  return s;
}

void check_threshold(double shadow_threshold) {
  if (!(shadow_threshold >= 0) || !std::isfinite(shadow_threshold))
    fail("light statistics: shadow_threshold must be a number ≥ 0, got {}", shadow_threshold);
}

// Each frame's sum of values, clipped count and count at or below
// `threshold` over pixels [0, pixels) of the row-major matrices, added to
// sums[i], saturated[i], dark[i]. Pixel by pixel along the rows, four frames
// to a vector: each frame's sum still runs over the pixels in order (the
// same double as one frame at a time).
LIGHTSTAGE_SIMD_CLONES void tally_frames(const float* values, const bool* clipped, std::size_t pixels,
                                         std::size_t frames, double threshold, double* sums,
                                         std::int64_t* saturated, std::int64_t* dark) {
  using Doubles = double __attribute__((vector_size(4 * sizeof(double))));
  using Floats = float __attribute__((vector_size(4 * sizeof(float))));
  using Counts = std::int64_t __attribute__((vector_size(4 * sizeof(std::int64_t))));
  const std::size_t vectors = frames / 4 * 4;
  for (std::size_t p = 0; p < pixels; ++p) {
    const float* row = values + p * frames;
    const bool* flags = clipped + p * frames;
    for (std::size_t i = 0; i < vectors; i += 4) {
      Floats f;
      Doubles sum;
      Counts clip, shadow;
      std::memcpy(&f, row + i, sizeof f);
      std::memcpy(&sum, sums + i, sizeof sum);
      std::memcpy(&clip, saturated + i, sizeof clip);
      std::memcpy(&shadow, dark + i, sizeof shadow);
      const Doubles v = __builtin_convertvector(f, Doubles);
      sum += v;
      clip += Counts{flags[i], flags[i + 1], flags[i + 2], flags[i + 3]};
      shadow -= v <= threshold;  // a set lane is −1
      std::memcpy(sums + i, &sum, sizeof sum);
      std::memcpy(saturated + i, &clip, sizeof clip);
      std::memcpy(dark + i, &shadow, sizeof shadow);
    }
    for (std::size_t i = vectors; i < frames; ++i) {
      sums[i] += row[i];
      saturated[i] += flags[i] ? 1 : 0;
      dark[i] += static_cast<double>(row[i]) <= threshold ? 1 : 0;
    }
  }
}

}  // namespace

std::vector<std::string> frame_files(const ImageStack& stack) {
  std::vector<std::string> files;
  for (const Frame& frame : stack.frames) files.push_back(frame.filename);
  return files;
}

nlohmann::json LightStatistics::to_json() const {
  return {{"file", file},
          {"led_id", led_id},
          {"direction", {direction.x(), direction.y(), direction.z()}},
          {"exposure_us", exposure_us},
          {"gain", gain},
          {"mean_value", mean_value},
          {"saturated_share", saturated_share},
          {"shadow_share", shadow_share}};
}

std::vector<LightStatistics> light_statistics(const ImageStack& stack, double shadow_threshold,
                                              const RadiometryOptions& radiometry) {
  return light_statistics(stack, make_observations(stack, radiometry), shadow_threshold);
}

std::vector<LightStatistics> light_statistics(const ImageStack& stack, const Observations& observations,
                                              double shadow_threshold) {
  check_threshold(shadow_threshold);
  LightStatisticsTally tally(frame_files(stack), {shadow_threshold, ""});
  tally.add(observations);
  return tally.statistics(stack);
}

StatisticsThreshold statistics_threshold(const nlohmann::json& solve_parameters, std::optional<double> flag) {
  if (flag) return {*flag, "--shadow-threshold"};
  if (solve_parameters.is_object()) {
    const auto it = solve_parameters.find("shadow_threshold");
    if (it != solve_parameters.end() && it->is_number() && it->get<double>() > 0)
      return {it->get<double>(), "the solver's"};
  }
  return {kDefaultShadowThreshold, "the default"};
}

LightStatisticsTally::LightStatisticsTally(std::vector<std::string> files, StatisticsThreshold threshold)
    : files_(std::move(files)),
      threshold_(std::move(threshold)),
      sums_(files_.size(), 0.0),
      saturated_(files_.size(), 0),
      shadow_(files_.size(), 0) {
  check_threshold(threshold_.value);
}

void LightStatisticsTally::add(const Observations& observations) {
  if (observations.image_count() != files_.size())
    fail("light statistics: {} observation columns for {} frames", observations.image_count(), files_.size());
  const std::size_t frames = files_.size();
  std::vector<double> sums(frames, 0.0);
  std::vector<std::int64_t> saturated(frames, 0), dark(frames, 0);
  tally_frames(observations.intensities.data(), observations.saturated.data(), observations.pixel_count(),
               frames, threshold_.value, sums.data(), saturated.data(), dark.data());
  for (std::size_t i = 0; i < frames; ++i) {
    sums_[i] += sums[i];
    saturated_[i] += static_cast<std::size_t>(saturated[i]);
    shadow_[i] += static_cast<std::size_t>(dark[i]);
  }
  pixels_ += observations.pixel_count();
}

void LightStatisticsTally::add(const LightStatisticsTally& other) {
  if (other.files_ != files_)
    fail("light statistics: parts of different frames ({} and {} files)", files_.size(), other.files_.size());
  if (other.threshold_.value != threshold_.value)
    fail("light statistics: parts counted with different shadow thresholds ({} and {})", threshold_.value,
         other.threshold_.value);
  for (std::size_t i = 0; i < files_.size(); ++i) {
    sums_[i] += other.sums_[i];
    saturated_[i] += other.saturated_[i];
    shadow_[i] += other.shadow_[i];
  }
  pixels_ += other.pixels_;
}

std::vector<LightStatistics> LightStatisticsTally::statistics(const ImageStack& stack) const {
  if (stack.frames.size() != files_.size())
    fail("light statistics: {} frames in the stack, {} counted", stack.frames.size(), files_.size());
  std::vector<LightStatistics> out;
  const auto n = static_cast<double>(pixels_);
  for (std::size_t i = 0; i < files_.size(); ++i) {
    LightStatistics s = frame_statistics(stack.frames[i]);
    if (pixels_ > 0) {
      s.mean_value = sums_[i] / n;
      s.saturated_share = static_cast<double>(saturated_[i]) / n;
      s.shadow_share = static_cast<double>(shadow_[i]) / n;
    }
    out.push_back(s);
  }
  return out;
}

nlohmann::json LightStatisticsTally::summary_json() const {
  nlohmann::json frames = nlohmann::json::array();
  const auto n = static_cast<double>(pixels_);
  for (std::size_t i = 0; i < files_.size(); ++i) {
    frames.push_back({{"file", files_[i]},
                      {"mean_value", pixels_ > 0 ? sums_[i] / n : 0.0},
                      {"saturated_share", pixels_ > 0 ? static_cast<double>(saturated_[i]) / n : 0.0},
                      {"shadow_share", pixels_ > 0 ? static_cast<double>(shadow_[i]) / n : 0.0}});
  }
  return {{"shadow_threshold", threshold_.value},
          {"threshold_source", threshold_.source},
          {"pixels", pixels_},
          {"frames", frames}};
}

nlohmann::json LightStatisticsTally::to_json() const {
  return {{"files", files_},
          {"shadow_threshold", threshold_.value},
          {"threshold_source", threshold_.source},
          {"pixels", pixels_},
          {"sums", sums_},
          {"saturated", saturated_},
          {"shadow", shadow_}};
}

LightStatisticsTally LightStatisticsTally::from_json(const nlohmann::json& j, const std::string& what) {
  try {
    LightStatisticsTally tally(
        j.at("files").get<std::vector<std::string>>(),
        {j.at("shadow_threshold").get<double>(), j.at("threshold_source").get<std::string>()});
    tally.pixels_ = j.at("pixels").get<std::size_t>();
    tally.sums_ = j.at("sums").get<std::vector<double>>();
    tally.saturated_ = j.at("saturated").get<std::vector<std::size_t>>();
    tally.shadow_ = j.at("shadow").get<std::vector<std::size_t>>();
    const std::size_t n = tally.files_.size();
    if (tally.sums_.size() != n || tally.saturated_.size() != n || tally.shadow_.size() != n)
      fail("{}: light statistics: sums and counts for {} files expected", what, n);
    return tally;
  } catch (const nlohmann::json::exception& e) {
    fail("{}: light statistics: {}", what, e.what());
  }
}

std::optional<StatisticsThreshold> recorded_threshold(const nlohmann::json& recorded) {
  if (!recorded.is_object()) return std::nullopt;
  const auto value = recorded.find("shadow_threshold");
  const auto source = recorded.find("threshold_source");
  if (value == recorded.end() || !value->is_number() || !(value->get<double>() >= 0) ||
      !std::isfinite(value->get<double>()) || source == recorded.end() || !source->is_string())
    return std::nullopt;
  return StatisticsThreshold{value->get<double>(), source->get<std::string>()};
}

std::optional<std::vector<LightStatistics>> recorded_light_statistics(const nlohmann::json& recorded,
                                                                      const ImageStack& stack) {
  if (!recorded_threshold(recorded)) return std::nullopt;
  const auto frames = recorded.find("frames");
  if (frames == recorded.end() || !frames->is_array() || frames->size() != stack.frames.size())
    return std::nullopt;
  std::vector<LightStatistics> out;
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    const nlohmann::json& f = (*frames)[i];
    if (!f.is_object()) return std::nullopt;
    const auto file = f.find("file");
    if (file == f.end() || !file->is_string() || file->get<std::string>() != stack.frames[i].filename)
      return std::nullopt;
    LightStatistics s = frame_statistics(stack.frames[i]);
    for (auto [key, value] :
         {std::pair{"mean_value", &s.mean_value}, std::pair{"saturated_share", &s.saturated_share},
          std::pair{"shadow_share", &s.shadow_share}}) {
      const auto it = f.find(key);
      if (it == f.end() || !it->is_number() || !std::isfinite(it->get<double>())) return std::nullopt;
      *value = it->get<double>();
    }
    out.push_back(s);
  }
  return out;
}

}  // namespace lightstage::report
