#pragma once
// Angular error between predicted and ground-truth normal maps, as the
// DiLiGenT benchmark reports it: per pixel angle in degrees, then statistics
// over the pixels inside the mask where both maps hold a normal.

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace lightstage {

struct AngularErrorStats {
  double mean = 0;          // degrees
  double median = 0;        // degrees (percentiles interpolate linearly)
  double p90 = 0;           // degrees, 90th percentile
  double max = 0;           // degrees
  std::size_t count = 0;    // pixels compared
  std::size_t missing = 0;  // pixels in the mask with ground truth but no prediction

  nlohmann::json to_json() const;
  // One line for people: "angular error over N pixels: mean ... deg, ...".
  std::string describe() const;
};

struct AngularErrorMap {
  cv::Mat degrees;  // CV_32FC1, angle per compared pixel, 0 elsewhere
  cv::Mat valid;    // CV_8UC1, 255 where compared
  AngularErrorStats stats;
};

// Compares two CV_32FC3 (x, y, z) normal maps of the same size inside `mask`
// (CV_8UC1, nonzero = inside; empty = everywhere). A normal is present where
// it is finite and non-zero. Throws InputError for mismatched sizes or types.
AngularErrorMap angular_error(const cv::Mat& predicted, const cv::Mat& truth, const cv::Mat& mask = {});

// angular_error's statistics gathered band by band (a stack solved in bands):
// the bands' maps added top to bottom give the whole image's statistics.
class AngularErrorAccumulator {
 public:
  // As angular_error; with `map` (sized like `truth`) also fills its degrees and valid maps.
  void add(const cv::Mat& predicted, const cv::Mat& truth, const cv::Mat& mask = {},
           AngularErrorMap* map = nullptr);
  AngularErrorStats stats();  // sorts the errors gathered (in place: a copy would double them)
  // The errors gathered, in the order their pixels were added (until stats()).
  const std::vector<double>& errors() const { return errors_; }

 private:
  std::vector<double> errors_;
  double sum_ = 0;
  std::size_t missing_ = 0;
};

// Loads a predicted normal map (project encoding) and a ground-truth folder
// holding Normal_gt.png and mask.png (the mask is optional: then the ground
// truth's own valid pixels), and compares them. Errors name the file.
AngularErrorStats evaluate_normal_map(const std::filesystem::path& predicted_png,
                                      const std::filesystem::path& truth_dir);

}  // namespace lightstage
