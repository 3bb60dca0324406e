#include "lightstage/pipeline/solve_checks.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/geometry.hpp"

#include <fmt/format.h>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>

namespace lightstage::pipeline {
namespace {

// A singular value under this fraction of the largest is a missing dimension:
// far below what any real light layout has (a 5° cone: ~0.06).
constexpr double kRankTolerance = 1e-3;

bool is_bipolynomial(const std::string& method) {
  return method == "bilinear" || method == "biquadratic" || method == "bicubic";
}

}  // namespace

void check_light_rank(const Observations& observations) {
  const auto lights = static_cast<int>(observations.lights.rows());
  if (lights < 3) fail("light directions: {} light(s), at least 3 are needed to determine a normal", lights);
  const Eigen::JacobiSVD<Eigen::MatrixX3d> svd(observations.lights);
  const Eigen::Vector3d s = svd.singularValues();
  const int rank =
      s(0) <= 0 ? 0 : 1 + (s(1) > kRankTolerance * s(0) ? 1 : 0) + (s(2) > kRankTolerance * s(0) ? 1 : 0);
  if (rank >= 3) return;
  if (rank <= 1)
    fail(
        "light directions: rank {} < 3: all {} lights have the same direction (a normal needs three "
        "independent ones)",
        rank, lights);
  fail(
      "light directions: rank 2 < 3: all {} lights lie in one plane through the object (collinear on the "
      "dome, e.g. one arc); a normal needs three independent directions",
      lights);
}

double light_cone_deg(const Observations& observations) {
  double min_z = 1;
  for (Eigen::Index j = 0; j < observations.lights.rows(); ++j)
    min_z = std::min(min_z, observations.lights(j, 2));
  return deg_from_rad(std::acos(std::clamp(min_z, -1.0, 1.0)));
}

std::vector<std::string> method_warnings(const std::string& method, const Observations& observations) {
  std::vector<std::string> warnings;
  if (method == "l2" || method == "shape-prior") return warnings;
  const auto lights = static_cast<int>(observations.image_count());
  if (lights < kFewLights)
    warnings.push_back(
        fmt::format("{}: only {} lights: too few to reject shadows and highlights and fit a reflectance per "
                    "pixel; expect "
                    "errors of several degrees",
                    method, lights));
  if ((is_bipolynomial(method) || method == "auto") && lights < kMinBipolynomialLights)
    warnings.push_back(
        fmt::format("{}: {} lights, under the {} a bi-polynomial reflectance fit per pixel needs (T_low "
                    "keeps a quarter of "
                    "them)",
                    method, lights, kMinBipolynomialLights));
  const double cone = light_cone_deg(observations);
  if (method == "monotonic" && cone < kMonotonicMinConeDeg)
    warnings.push_back(fmt::format(
        "monotonic: the lights span only {:.0f} deg from the view axis; its elevation search needs lights "
        "over the hemisphere (at least {:.0f} deg)",
        cone, kMonotonicMinConeDeg));
  if (method == "auto" && cone < kMonotonicMinConeDeg)
    warnings.push_back(fmt::format(
        "auto: the lights span only {:.0f} deg from the view axis (under {:.0f}): its monotonic candidate is "
        "not used, the answer is biquadratic's",
        cone, kMonotonicMinConeDeg));
  return warnings;
}

std::size_t clamp_facing_away(SolveResult& result) {
  std::size_t count = 0;
  for (int y = 0; y < result.normals.rows; ++y) {
    auto* n = result.normals.ptr<cv::Vec3f>(y);
    const auto* solved = result.solved.ptr<std::uint8_t>(y);
    for (int x = 0; x < result.normals.cols; ++x) {
      if (solved[x] == 0 || !(n[x][2] < 0)) continue;
      ++count;
      n[x] = on_horizon(n[x]);
    }
  }
  return count;
}

}  // namespace lightstage::pipeline
