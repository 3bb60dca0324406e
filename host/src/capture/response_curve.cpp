#include "lightstage/host/capture/response_curve.hpp"

#include "lightstage/common/error.hpp"
#include "util/atomic_file.hpp"

#include <fmt/format.h>
#include <opencv2/photo.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>

namespace lightstage {
namespace {

double full_scale(int bits) { return std::ldexp(1.0, bits) - 1; }

double median_of(std::vector<double> v) {
  if (v.empty()) return 0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

InverseResponse InverseResponse::identity(int bits) { return InverseResponse(bits, {0.0, 1.0}); }

InverseResponse::InverseResponse(int bits, std::vector<double> knots)
    : bits_(bits), knots_(std::move(knots)) {
  if (bits_ < 1 || bits_ > 16) fail("response: bits {} is not in 1..16", bits_);
  if (knots_.size() < 2) fail("response: needs at least 2 knots, got {}", knots_.size());
  for (std::size_t i = 1; i < knots_.size(); ++i) {
    if (!(knots_[i] >= knots_[i - 1]))
      fail("response: knots must not decrease (knot {} < knot {})", i, i - 1);
  }
  if (!(knots_.back() > 0)) fail("response: the last knot must be positive");
}

double InverseResponse::at(double dn) const {
  const double x = std::clamp(dn / full_scale(bits_), 0.0, 1.0) * static_cast<double>(knots_.size() - 1);
  const auto i = std::min(static_cast<std::size_t>(x), knots_.size() - 2);
  const double f = x - static_cast<double>(i);
  return knots_[i] + f * (knots_[i + 1] - knots_[i]);
}

cv::Mat InverseResponse::linearise(const cv::Mat& image) const {
  if (image.channels() != 1 || (image.depth() != CV_8U && image.depth() != CV_16U)) {
    fail("response: linearise needs an 8- or 16-bit single-channel image, got type {}", image.type());
  }
  // A table over every possible stored value.
  const int levels = image.depth() == CV_8U ? 256 : 65536;
  std::vector<float> table(static_cast<std::size_t>(levels));
  for (int v = 0; v < levels; ++v) table[static_cast<std::size_t>(v)] = static_cast<float>(at(v));
  cv::Mat out(image.size(), CV_32FC1);
  for (int r = 0; r < image.rows; ++r) {
    float* dst = out.ptr<float>(r);
    if (image.depth() == CV_8U) {
      const auto* src = image.ptr<std::uint8_t>(r);
      for (int c = 0; c < image.cols; ++c) dst[c] = table[src[c]];
    } else {
      const auto* src = image.ptr<std::uint16_t>(r);
      for (int c = 0; c < image.cols; ++c) dst[c] = table[src[c]];
    }
  }
  return out;
}

nlohmann::json InverseResponse::to_json() const {
  return {{"format", "lightstage-response"}, {"version", 1}, {"bits", bits_}, {"knots", knots_}};
}

void InverseResponse::save(const std::filesystem::path& file) const {
  util::write_text_atomic(file, to_json().dump(2) + "\n");
}

InverseResponse InverseResponse::load(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) fail("{}: cannot read", file.string());
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    fail("{}: not JSON: {}", file.string(), e.what());
  }
  if (!j.is_object() || j.value("format", "") != "lightstage-response") {
    fail("{}: format: expected \"lightstage-response\"", file.string());
  }
  if (j.value("version", 0) != 1) fail("{}: version: expected 1", file.string());
  if (!j.contains("bits") || !j["bits"].is_number_integer())
    fail("{}: bits: expected an integer", file.string());
  if (!j.contains("knots") || !j["knots"].is_array())
    fail("{}: knots: expected an array of numbers", file.string());
  std::vector<double> knots;
  for (std::size_t i = 0; i < j["knots"].size(); ++i) {
    if (!j["knots"][i].is_number()) fail("{}: knots[{}]: expected a number", file.string(), i);
    knots.push_back(j["knots"][i].get<double>());
  }
  try {
    return InverseResponse(j["bits"].get<int>(), std::move(knots));
  } catch (const InputError& e) {
    fail("{}: {}", file.string(), e.what());
  }
}

std::vector<double> response_bracket_us(double reference_us) {
  std::vector<double> exposures;
  for (int i = 0; i < 8; ++i) exposures.push_back(reference_us / 16 * std::exp2(i));
  return exposures;
}

std::vector<double> linearity_bracket_us(double reference_us) {
  std::vector<double> exposures;
  for (int i = -2; i <= 2; ++i) exposures.push_back(reference_us * std::exp2(0.5 * i));
  return exposures;
}

namespace {

// Debevec–Malik weighs a value by its distance from the ends of the range, so
// the curve near 0 and near full scale is held only by its smoothness term,
// which bends it the wrong way (too bright in the shadows, flat towards the
// top). Within [kTrustedLow, kTrustedHigh] of the 8-bit range the data holds
// it; beyond, the curve goes on as the power law (a straight line in log-log)
// of the trusted values next to each end.
constexpr int kTrustedLow = 26;    // ~10% of full scale
constexpr int kTrustedHigh = 230;  // ~90%

// The slope of log radiance over log value, least squares over [first, last].
double log_log_slope(const std::vector<double>& log_radiance, int first, int last) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const int n = last - first + 1;
  for (int z = first; z <= last; ++z) {
    const double x = std::log(static_cast<double>(z));
    const double y = log_radiance[static_cast<std::size_t>(z)];
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  return slope > 0 && std::isfinite(slope) ? slope : 1.0;  // a fit that is no response: linear
}

void extend_ends(std::vector<double>& log_radiance) {
  const int top = static_cast<int>(log_radiance.size()) - 1;
  const auto extend = [&](int from, double slope, int z) {
    log_radiance[static_cast<std::size_t>(z)] =
        log_radiance[static_cast<std::size_t>(from)] +
        slope * (std::log(static_cast<double>(z)) - std::log(static_cast<double>(from)));
  };
  const double low_slope = log_log_slope(log_radiance, kTrustedLow, 2 * kTrustedLow);
  for (int z = 1; z < kTrustedLow; ++z) extend(kTrustedLow, low_slope, z);
  const double high_slope = log_log_slope(log_radiance, kTrustedHigh * 4 / 5, kTrustedHigh);
  for (int z = kTrustedHigh + 1; z <= top; ++z) extend(kTrustedHigh, high_slope, z);
}

}  // namespace

InverseResponse calibrate_response(const std::vector<cv::Mat>& images,
                                   const std::vector<double>& exposures_us, int bits) {
  if (images.size() != exposures_us.size()) {
    fail("response: {} images but {} exposures", images.size(), exposures_us.size());
  }
  if (images.size() < 3) fail("response: needs a bracket of at least 3 exposures, got {}", images.size());
  if (std::set<double>(exposures_us.begin(), exposures_us.end()).size() < 3) {
    fail("response: the bracket needs at least 3 different exposures");
  }
  // Debevec–Malik in OpenCV works on 8-bit values: deeper data is reduced to
  // its top 8 bits for the fit, and the 256-knot curve interpolates between.
  std::vector<cv::Mat> eight;
  std::vector<float> times;
  for (std::size_t i = 0; i < images.size(); ++i) {
    if (images[i].channels() != 1) fail("response: image {} is not single-channel", i);
    cv::Mat e;
    images[i].convertTo(e, CV_8U, 255.0 / full_scale(bits));
    cv::Mat rgb;
    cv::merge(std::vector<cv::Mat>{e, e, e}, rgb);  // the photo module expects 3 channels
    eight.push_back(rgb);
    times.push_back(static_cast<float>(exposures_us[i] * 1e-6));
  }
  cv::Mat curve;
  auto debevec = cv::createCalibrateDebevec(120, 10.0f, false);
  debevec->process(eight, curve, times);
  std::vector<double> log_radiance(256);
  for (int k = 0; k < 256; ++k) {
    const double value = curve.at<cv::Vec3f>(k)[0];
    if (!(value > 0) || !std::isfinite(value)) fail("response: the fit failed (no signal in the bracket?)");
    log_radiance[static_cast<std::size_t>(k)] = std::log(value);
  }
  extend_ends(log_radiance);
  // Scale so full scale is 1; monotone against what noise is left.
  std::vector<double> knots(256);
  knots[0] = 0;
  for (std::size_t k = 1; k < knots.size(); ++k)
    knots[k] = std::max(std::exp(log_radiance[k] - log_radiance.back()), knots[k - 1]);
  knots.back() = 1;
  return InverseResponse(bits, std::move(knots));
}

nlohmann::json LinearityReport::to_json() const {
  return {{"exposures_us", exposures_us},
          {"relative_ratio", relative_ratio},
          {"max_deviation", max_deviation},
          {"pixels_used", pixels_used}};
}

LinearityReport check_linearity(const std::vector<cv::Mat>& images, const std::vector<double>& exposures_us,
                                const InverseResponse& response, double low, double high) {
  if (images.size() != exposures_us.size() || images.size() < 2) {
    fail("linearity: needs at least 2 images with their exposures, got {} and {}", images.size(),
         exposures_us.size());
  }
  std::vector<cv::Mat> linear;
  for (const auto& image : images) linear.push_back(response.linearise(image));
  // Pixels inside [low, high] of full scale in every frame: away from noise and clipping.
  cv::Mat usable(linear[0].size(), CV_8UC1, cv::Scalar(255));
  for (const auto& l : linear) {
    cv::Mat in_range;
    cv::inRange(l, low, high, in_range);
    usable &= in_range;
  }
  LinearityReport report;
  report.exposures_us = exposures_us;
  report.pixels_used = static_cast<std::size_t>(cv::countNonZero(usable));
  if (report.pixels_used == 0) {
    fail("linearity: no pixel stays within [{}, {}] of full scale in every frame; narrow the bracket", low,
         high);
  }
  std::vector<double> medians;
  for (std::size_t i = 0; i < linear.size(); ++i) {
    std::vector<double> ratio;
    for (int r = 0; r < usable.rows; ++r) {
      for (int c = 0; c < usable.cols; ++c) {
        if (usable.at<std::uint8_t>(r, c)) ratio.push_back(linear[i].at<float>(r, c) / exposures_us[i]);
      }
    }
    medians.push_back(median_of(ratio));
  }
  const double overall = median_of(medians);
  for (const double m : medians) {
    report.relative_ratio.push_back(m / overall);
    report.max_deviation = std::max(report.max_deviation, std::abs(m / overall - 1));
  }
  return report;
}

}  // namespace lightstage
