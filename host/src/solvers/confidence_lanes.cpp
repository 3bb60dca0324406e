#include "solvers/confidence_lanes.hpp"

#include "lightstage/common/geometry.hpp"
#include "lightstage/common/select_kth.hpp"
#include "lightstage/common/simd_clones.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

namespace lightstage {
namespace {

// Inliers whose Gram matrix is this close to singular (smallest over largest
// eigenvalue) leave the normal undetermined.
constexpr double kMinEigenvalueRatio = 1e-6;

// The first pass: each light's value at unit light and misfit, NaN where
// the light is not counted (not lit, or from behind the answer: the model
// has no slope there); each lane's counted misfits in light order into
// magnitude[lane]; per lane the counted lights and their values' sum.
LIGHTSTAGE_SIMD_CLONES void misfits(const LightLanes& lanes, const PixelLanes& nx, const PixelLanes& ny,
                                    const PixelLanes& nz, const PixelLanes& albedo, double shadow_threshold,
                                    PixelLanes* values, PixelLanes* misfit, double* const* magnitude,
                                    std::size_t* lit, PixelLanes& lit_sum) {
  const PixelLanes not_counted = PixelLanes{} + std::numeric_limits<double>::quiet_NaN(), zero = {};
  const PixelMask magnitude_bits = ~__builtin_bit_cast(PixelMask, -PixelLanes{});  // all but the sign (of −0)
  const PixelLanes* gain = lanes.near_lights() ? lanes.gain.data() : nullptr;
  const std::size_t images = lanes.images();
  PixelLanes sum = {};
  for (std::size_t j = 0; j < images; ++j) {
    const PixelLanes value = gain != nullptr ? lanes.observed[j] / gain[j] : lanes.observed[j];
    values[j] = value;
    const PixelLanes shading = lanes.x[j] * nx + lanes.y[j] * ny + lanes.z[j] * nz;
    const PixelLanes m = __builtin_bit_cast(
        PixelLanes, __builtin_bit_cast(PixelMask, value - albedo * shading) & magnitude_bits);
    // Bitwise, not short-circuit: all three are cheap, and a branch on each would mispredict.
    const PixelMask counted = (value - value == zero) & (lanes.unsaturated[j] != zero) &
                              (value > shadow_threshold) & (shading > zero);
    // NaN compares false against any cut, an infinite one too.
    misfit[j] = counted ? m : not_counted;
    sum += counted ? value : zero;
    // Written whatever the test says, kept by advancing: no branch to mispredict.
    for (std::size_t lane = 0; lane < kPixelLanes; ++lane) {
      magnitude[lane][lit[lane]] = m[lane];
      lit[lane] += static_cast<std::size_t>(counted[lane] & 1);
    }
  }
  lit_sum = sum;
}

// Σ l lᵀ and Σ v l over the inliers (misfit within the cut), their count,
// and each light's floored r² (0 for an outlier) into `squared`. An outlier
// adds exact zeros; its value and misfit are not read.
LIGHTSTAGE_SIMD_CLONES void inlier_sums(const LightLanes& lanes, const PixelLanes* values,
                                        const PixelLanes* misfit, const PixelLanes& cut,
                                        const PixelLanes& floor, NormalEquationLanes& sums,
                                        PixelLanes (&inliers)[2], PixelLanes* squared) {
  // Local sums (kept in registers: `squared` could alias the caller's).
  NormalEquationLanes local;
  PixelLanes count[2] = {};
  const PixelLanes zero = {}, one = PixelLanes{} + 1.0;
  const auto add = [&](int set, std::size_t j) __attribute__((always_inline)) {
    const PixelMask inlier = misfit[j] <= cut;
    local.add(set, inlier, lanes.x[j], lanes.y[j], lanes.z[j], values[j]);
    count[set] += inlier ? one : zero;
    const PixelLanes r = inlier ? (misfit[j] < floor ? floor : misfit[j]) : zero;
    squared[j] = r * r;
  };
  for_each_light_in_two_sets(lanes.images(), add);
  sums = local;
  inliers[0] = count[0];
  inliers[1] = count[1];
}

// S = Σ r² l lᵀ, upper triangle, in two sets (even and odd lights).
LIGHTSTAGE_SIMD_CLONES void sandwich_sums(const LightLanes& lanes, const PixelLanes* squared,
                                          PixelLanes (&sandwich)[2][6]) {
  PixelLanes local[2][6] = {};
  const auto add = [&](int set, std::size_t j) __attribute__((always_inline)) {
    PixelLanes* s = local[set];
    const PixelLanes x = lanes.x[j], y = lanes.y[j], z = lanes.z[j], r2 = squared[j];
    s[0] += r2 * (x * x);
    s[1] += r2 * (x * y);
    s[2] += r2 * (x * z);
    s[3] += r2 * (y * y);
    s[4] += r2 * (y * z);
    s[5] += r2 * (z * z);
  };
  for_each_light_in_two_sets(lanes.images(), add);
  for (int set = 0; set < 2; ++set)
    for (int k = 0; k < 6; ++k) sandwich[set][k] = local[set][k];
}

// The predicted error from the inliers' sums: the sandwich's spread about
// n and the inliers' own normal's disagreement with it.
double error_from_sums(const Eigen::Matrix3d& gram, const Eigen::Matrix3d& meat,
                       const Eigen::Vector3d& moment, const Eigen::Vector3d& n, double albedo) {
  const double infinite = std::numeric_limits<double>::infinity();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(gram);
  const Eigen::Vector3d lambda = eigen.eigenvalues();
  if (!(lambda(0) > kMinEigenvalueRatio * lambda(2))) return infinite;
  const Eigen::Matrix3d& v = eigen.eigenvectors();
  const Eigen::Matrix3d inverse = v * lambda.cwiseInverse().asDiagonal() * v.transpose();
  const Eigen::Matrix3d tangent = Eigen::Matrix3d::Identity() - n * n.transpose();
  const Eigen::Matrix3d bread = tangent * inverse;
  const double spread =
      deg_from_rad(std::sqrt(std::max(0.0, (bread * meat * bread.transpose()).trace())) / albedo);
  const Eigen::Vector3d fitted = inverse * moment;
  const double disagreement = fitted.squaredNorm() > 0 ? angle_between_deg(fitted, n) : 180.0;
  return std::hypot(spread, disagreement);
}

}  // namespace

void ConfidenceLanes::predict(const LightLanes& lanes, const Eigen::Vector3d* normals, const double* albedo,
                              const bool* judged, double* errors) {
  const double infinite = std::numeric_limits<double>::infinity();
  const std::size_t images = lanes.images();
  values_.resize(images);
  misfit_.resize(images);
  squared_.resize(images);
  double* magnitude[kPixelLanes];
  for (std::size_t lane = 0; lane < kPixelLanes; ++lane) {
    magnitude_[lane].resize(images);
    magnitude[lane] = magnitude_[lane].data();
  }
  // Lanes not judged take a harmless answer; their sums are not read.
  PixelLanes nx = {}, ny = {}, nz = PixelLanes{} + 1.0, rho = PixelLanes{} + 1.0;
  for (std::size_t lane = 0; lane < lanes.used; ++lane) {
    if (!judged[lane]) continue;
    nx[lane] = normals[lane].x();
    ny[lane] = normals[lane].y();
    nz[lane] = normals[lane].z();
    rho[lane] = albedo[lane];
  }
  std::size_t lit[kPixelLanes] = {};
  PixelLanes lit_sum = {};
  misfits(lanes, nx, ny, nz, rho, options_.shadow_threshold, values_.data(), misfit_.data(), magnitude, lit,
          lit_sum);
  PixelLanes cut = {}, floor = {};
  bool open[kPixelLanes] = {};
  bool any = false;
  for (std::size_t lane = 0; lane < lanes.used; ++lane) {
    if (!judged[lane]) continue;
    errors[lane] = infinite;
    if (!(albedo[lane] > 0 && std::isfinite(albedo[lane])) || lit[lane] < 3) continue;
    floor[lane] = options_.min_relative_sigma * lit_sum[lane] / static_cast<double>(lit[lane]);
    // Three lit lights leave no spare one to judge them by: all are inliers (the
    // cut at twice their median would drop one whenever rounding decides).
    const auto half = static_cast<std::ptrdiff_t>(lit[lane] / 2);
    cut[lane] =
        lit[lane] == 3
            ? infinite
            : std::max(floor[lane], options_.trim * select_kth(magnitude[lane],
                                                               static_cast<std::ptrdiff_t>(lit[lane]), half));
    open[lane] = any = true;
  }
  if (!any) return;
  NormalEquationLanes sums;
  PixelLanes inliers[2] = {};
  inlier_sums(lanes, values_.data(), misfit_.data(), cut, floor, sums, inliers, squared_.data());
  PixelLanes sandwich[2][6] = {};
  sandwich_sums(lanes, squared_.data(), sandwich);
  for (std::size_t lane = 0; lane < lanes.used; ++lane) {
    if (!open[lane] || inliers[0][lane] + inliers[1][lane] < 3) continue;
    errors[lane] = error_from_sums(sums.gram_matrix(lane), NormalEquationLanes::symmetric(sandwich, lane),
                                   sums.moment_vector(lane), normals[lane], albedo[lane]);
  }
}

}  // namespace lightstage
