#pragma once
// The confidence's predicted error (normal_confidence.hpp) of up to
// kPixelLanes pixels at once, one per lane, from their lights as l2 or the
// separate pass loaded them (pixel_lanes.hpp). A pixel's error is the same
// float in any lane.

#include "lightstage/host/solvers/confidence_options.hpp"
#include "solvers/pixel_lanes.hpp"

#include <Eigen/Core>

#include <array>
#include <vector>

namespace lightstage {

class ConfidenceLanes {
 public:
  explicit ConfidenceLanes(const ConfidenceOptions& options) : options_(options) {}

  // errors[lane] for every lane of `lanes` in use (LightLanes::used): the predicted error in
  // degrees at the answer (normals[lane] unit, albedo[lane]); +inf where the
  // albedo is not positive and finite, fewer than three inliers remain or
  // they are coplanar. Lanes not `judged` are left as they are. Keeps its
  // working arrays from group to group: one per thread.
  void predict(const LightLanes& lanes, const Eigen::Vector3d* normals, const double* albedo,
               const bool* judged, double* errors);

 private:
  ConfidenceOptions options_;
  LaneBuffer values_;   // per image: the value at unit light
  LaneBuffer misfit_;   // per image: |v − ρ lᵀn|; NaN where not lit or facing away
  LaneBuffer squared_;  // per image: the floored r² of an inlier, else 0
  std::array<std::vector<double>, kPixelLanes> magnitude_;  // per lane: its lit lights' misfits, in order
};

}  // namespace lightstage
