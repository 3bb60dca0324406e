#include "lightstage/host/capture/hdr_merge.hpp"

#include "lightstage/common/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace lightstage {
namespace {

double type_full_scale(int depth) { return depth == CV_8U ? 255.0 : 65535.0; }

// One sample as the merge reads it.
struct SampleView {
  const cv::Mat* image = nullptr;
  cv::Mat dark;  // CV_32F, or empty
  double seconds = 0;
};

template <typename T>
void merge_values(const std::vector<SampleView>& samples, double full, double sensor_full,
                  double saturation_dn, const std::vector<float>* table, HdrMerge& out) {
  const cv::Mat& first = *samples.front().image;
  const int values_per_row = first.cols * first.channels();
  const auto level = static_cast<float>(out.saturation_level);
  const float below_level = std::nextafter(level, 0.0f);
  for (int r = 0; r < first.rows; ++r) {
    float* dst = out.image.ptr<float>(r);
    for (int v = 0; v < values_per_row; ++v) {
      double weighted = 0, weights = 0;
      double longest = -1, longest_value = 0;
      for (std::size_t i = 0; i < samples.size(); ++i) {
        const SampleView& s = samples[i];
        const double raw = static_cast<double>(s.image->ptr<T>(r)[v]);
        if (raw >= saturation_dn) {
          ++out.clipped[i];
          continue;
        }
        const double dark = s.dark.empty() ? 0.0 : static_cast<double>(s.dark.ptr<float>(r)[v]);
        const double linear =
            table != nullptr ? (*table)[static_cast<std::size_t>(raw)] - dark : (raw - dark) / full;
        if (s.seconds > longest) {
          longest = s.seconds;
          longest_value = linear / s.seconds;
        }
        const double z = raw / sensor_full;  // where in the sensor's own range (12-bit in 16-bit words)
        const double hat = std::max(0.0, std::min(z, 1.0 - z));
        weighted += hat * linear;
        weights += hat * s.seconds;
      }
      if (longest < 0) {
        dst[v] = level;
        ++out.saturated_values;
        continue;
      }
      const double merged = weights > 0 ? weighted / weights : longest_value;
      dst[v] = std::min(static_cast<float>(merged), below_level);
    }
  }
}

}  // namespace

void HdrMergeOptions::check() const {
  if (!(saturation_dn >= 0 && std::isfinite(saturation_dn)))
    fail("HdrMergeOptions.saturation_dn: must be 0 (automatic) or positive, got {}", saturation_dn);
}

HdrMerge merge_hdr(const std::vector<HdrSample>& samples, const HdrMergeOptions& options) {
  options.check();
  if (samples.empty()) fail("hdr merge: no samples");
  const cv::Mat& first = samples.front().image;
  if (first.empty() || (first.depth() != CV_8U && first.depth() != CV_16U)) {
    fail("hdr merge: sample 0 must be an 8- or 16-bit image, got type {}", first.type());
  }
  std::vector<SampleView> views;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const HdrSample& s = samples[i];
    if (s.image.size() != first.size() || s.image.type() != first.type()) {
      fail("hdr merge: sample {} is type {} of {}x{}, sample 0 type {} of {}x{}", i, s.image.type(),
           s.image.cols, s.image.rows, first.type(), first.cols, first.rows);
    }
    if (!(s.exposure_us > 0 && std::isfinite(s.exposure_us)))
      fail("hdr merge: sample {}: exposure must be positive, got {} us", i, s.exposure_us);
    SampleView view;
    view.image = &s.image;
    view.seconds = s.exposure_us * 1e-6;
    if (!s.dark.empty()) {
      if (s.dark.size() != first.size() || s.dark.channels() != first.channels()) {
        fail("hdr merge: sample {}: dark is {}x{} with {} channel(s), the image {}x{} with {}", i,
             s.dark.cols, s.dark.rows, s.dark.channels(), first.cols, first.rows, first.channels());
      }
      s.dark.convertTo(view.dark, CV_MAKETYPE(CV_32F, first.channels()));
    }
    views.push_back(std::move(view));
  }
  const double full = type_full_scale(first.depth());
  const double sensor_full = options.sensor_full_scale > 0 ? options.sensor_full_scale : full;
  const double saturation_dn =
      options.saturation_dn > 0 ? options.saturation_dn : kClippedShare * sensor_full;
  std::vector<float> table;
  if (options.response != nullptr) {
    table.resize(static_cast<std::size_t>(full) + 1);
    for (std::size_t v = 0; v < table.size(); ++v)
      table[v] = static_cast<float>(options.response->at(static_cast<double>(v)));
  }
  double shortest = views.front().seconds;
  for (const SampleView& v : views) shortest = std::min(shortest, v.seconds);

  HdrMerge out;
  out.image = cv::Mat(first.size(), CV_MAKETYPE(CV_32F, first.channels()));
  // Stored as float: the level is exactly the value written to clipped pixels.
  out.saturation_level = static_cast<double>(static_cast<float>(1.0 / shortest));
  out.clipped.assign(samples.size(), 0);
  const std::vector<float>* t = table.empty() ? nullptr : &table;
  if (first.depth() == CV_8U) {
    merge_values<std::uint8_t>(views, full, sensor_full, saturation_dn, t, out);
  } else {
    merge_values<std::uint16_t>(views, full, sensor_full, saturation_dn, t, out);
  }
  return out;
}

}  // namespace lightstage
