#pragma once
// The settings of the confidence every method's normals get
// (normal_confidence.hpp), apart from it so that a solver that predicts the
// error itself (l2, lambertian.hpp) can take them without the predictor.

#include <nlohmann/json.hpp>

namespace lightstage {

struct ConfidenceOptions {
  double shadow_threshold = 0;       // observations at or below it are not lit (the solve's threshold)
  double scale_deg = 1.0;            // s: the predicted error at which confidence is 0.5
  double trim = 2.0;                 // inliers: |r| at most this many times the median |r|
  double min_relative_sigma = 1e-3;  // |r| floor, relative to the pixel's mean lit value (quantisation)
  int threads = 0;                   // 0 = hardware concurrency (predict_normal_error)

  void check() const;  // throws InputError naming the field and value
  nlohmann::json to_json() const;
};

}  // namespace lightstage
