#pragma once
// A camera's inverse response: stored value (DN) -> relative linear radiance,
// for cameras that do not deliver raw, linear data (JPEG-tuned pipelines,
// gamma-encoded video modes). Calibrated from an exposure bracket of a still
// scene with OpenCV's photo module (Debevec & Malik), stored as JSON, applied
// to every frame of a capture so the stack on disk is linear.

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <filesystem>
#include <vector>

namespace lightstage {

class InverseResponse {
 public:
  // The identity for `bits`-bit data: value / (2^bits − 1).
  static InverseResponse identity(int bits);
  // Knots: radiance at DN = k / (n − 1) · full scale, k = 0 … n − 1, increasing, last = 1.
  InverseResponse(int bits, std::vector<double> knots);

  // Throws InputError naming the file and field.
  static InverseResponse load(const std::filesystem::path& file);
  void save(const std::filesystem::path& file) const;
  nlohmann::json to_json() const;

  // CV_8UC1 / CV_16UC1 → CV_32FC1 relative radiance (1 = the radiance that fills full scale).
  cv::Mat linearise(const cv::Mat& image) const;
  double at(double dn) const;  // piecewise linear between knots
  int bits() const { return bits_; }
  const std::vector<double>& knots() const { return knots_; }

 private:
  int bits_;
  std::vector<double> knots_;
};

// The default brackets around the rig camera's exposure `reference_us`. To
// fit a response: 8 exposures doubling from 1/16 of it, so every value from
// dark to clipped is seen. To check linearity: 5 exposures half a stop apart
// from half to twice it, so many pixels stay well inside the range in every
// frame (check_linearity uses only those).
std::vector<double> response_bracket_us(double reference_us);
std::vector<double> linearity_bracket_us(double reference_us);

// From frames of one still scene at several exposures (µs), all of `bits`-bit
// data. Throws InputError when fewer than 3 exposures or they do not differ.
// The ends of the curve, where few values are seen and the fit is loosely
// held, follow the power law of its well-determined middle: it reaches 0 at 0
// and does not flatten below full scale.
InverseResponse calibrate_response(const std::vector<cv::Mat>& images,
                                   const std::vector<double>& exposures_us, int bits);

// How linear the (linearised) data is: per pixel well inside the range in
// every frame, radiance / exposure should not depend on the exposure. Reports
// the deviation of each exposure's median ratio from the overall median.
struct LinearityReport {
  std::vector<double> exposures_us;
  std::vector<double> relative_ratio;  // per exposure, median(radiance/exposure) / overall, 1 = linear
  double max_deviation = 0;            // max |relative_ratio − 1|
  std::size_t pixels_used = 0;
  nlohmann::json to_json() const;
};

LinearityReport check_linearity(const std::vector<cv::Mat>& images, const std::vector<double>& exposures_us,
                                const InverseResponse& response, double low = 0.05, double high = 0.9);

}  // namespace lightstage
