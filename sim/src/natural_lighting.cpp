#include "lightstage/sim/natural_lighting.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace lightstage::sim {
namespace {

// Directions filling a cap of half-angle `half` around +z evenly (a Fibonacci
// spiral in solid angle), each standing for the same solid angle.
std::vector<Vec3> cap_samples(double half, int count) {
  std::vector<Vec3> dirs;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  const double cos_half = std::cos(half);
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - (1.0 - cos_half) * (i + 0.5) / count;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    dirs.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  return dirs;
}

// A rotation taking +z to `d`.
Mat3 frame_to(const Vec3& d) {
  return Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), d).toRotationMatrix();
}

}  // namespace

std::vector<double> sh_basis9(const Vec3& n) {
  const double x = n.x(), y = n.y(), z = n.z();
  return {0.282095,
          0.488603 * y,
          0.488603 * z,
          0.488603 * x,
          1.092548 * x * y,
          1.092548 * y * z,
          0.315392 * (3 * z * z - 1),
          1.092548 * x * z,
          0.546274 * (x * x - y * y)};
}

double NaturalLighting::irradiance(const Vec3& n, int samples) const {
  // Ambient from the whole sphere: ∫ max(n·ω, 0) dω / π = 1 per unit radiance.
  double e = ambient;
  // A uniform upper-hemisphere sky: (1 + n_z) / 2 per unit radiance.
  e += sky * 0.5 * (1.0 + n.z());
  for (const AreaLight& a : areas) {
    const Mat3 rot = frame_to(a.direction);
    const double solid_angle = 2 * kPi * (1 - std::cos(a.half_angle_rad));
    double sum = 0;
    const auto dirs = cap_samples(a.half_angle_rad, samples);
    for (const Vec3& d : dirs) sum += std::max(0.0, n.dot(rot * d));
    e += a.radiance * solid_angle / kPi * sum / static_cast<double>(dirs.size());
  }
  if (!sh.empty()) {
    // Ramamoorthi & Hanrahan: E = Σ Â_l L_lm Y_lm(n), Â = π, 2π/3, π/4; /π for our convention.
    static constexpr double kBand[9] = {1.0, 2.0 / 3, 2.0 / 3, 2.0 / 3, 0.25, 0.25, 0.25, 0.25, 0.25};
    const auto y = sh_basis9(n);
    for (std::size_t i = 0; i < sh.size() && i < 9; ++i) e += kBand[i] * sh[i] * y[i];
  }
  return std::max(e, 0.0);
}

nlohmann::json NaturalLighting::describe() const {
  nlohmann::json areas_json = nlohmann::json::array();
  for (const AreaLight& a : areas)
    areas_json.push_back({{"direction", {a.direction.x(), a.direction.y(), a.direction.z()}},
                          {"half_angle_deg", deg_from_rad(a.half_angle_rad)},
                          {"radiance", a.radiance}});
  nlohmann::json j{{"areas", areas_json}, {"sky", sky}, {"ambient", ambient}};
  if (!sh.empty()) j["sh"] = sh;
  return j;
}

void NaturalLightingOptions::check() const {
  if (images < 1 || images > 10000) fail("natural lighting: images must be in 1..10000, got {}", images);
  if (min_area_lights < 1 || max_area_lights < min_area_lights || max_area_lights > 64)
    fail("natural lighting: area lights per image must satisfy 1 <= min <= max <= 64, got {}..{}",
         min_area_lights, max_area_lights);
  if (!(min_half_angle_deg > 0) || max_half_angle_deg < min_half_angle_deg || max_half_angle_deg > 60)
    fail("natural lighting: half angles must satisfy 0 < min <= max <= 60 deg, got {}..{}",
         min_half_angle_deg, max_half_angle_deg);
  if (!(min_elevation_deg >= 0 && min_elevation_deg < 90))
    fail("natural lighting: min_elevation_deg must be in [0, 90), got {}", min_elevation_deg);
  if (!(min_ambient >= 0) || max_ambient < min_ambient)
    fail("natural lighting: ambient must satisfy 0 <= min <= max, got {}..{}", min_ambient, max_ambient);
  if (!(sh_variation >= 0)) fail("natural lighting: sh_variation must be >= 0, got {}", sh_variation);
}

std::vector<NaturalLighting> random_natural_lighting(const NaturalLightingOptions& options) {
  options.check();
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  auto between = [&](double lo, double hi) { return lo + (hi - lo) * uniform(rng); };
  std::vector<NaturalLighting> out;
  for (int i = 0; i < options.images; ++i) {
    NaturalLighting l;
    if (options.kind == NaturalLightingKind::kAreaLights) {
      const int n = options.min_area_lights +
                    static_cast<int>(uniform(rng) * (options.max_area_lights - options.min_area_lights + 1));
      double strongest = 0;
      for (int k = 0; k < std::min(n, options.max_area_lights); ++k) {
        // Uniform over the part of the hemisphere above min elevation.
        const double z = between(std::sin(rad_from_deg(options.min_elevation_deg)), 1.0);
        const double phi = between(0, 2 * kPi);
        const double r = std::sqrt(1 - z * z);
        AreaLight a;
        a.direction = Vec3(r * std::cos(phi), r * std::sin(phi), z);
        a.half_angle_rad = rad_from_deg(between(options.min_half_angle_deg, options.max_half_angle_deg));
        // Radiance so that its irradiance at normal incidence lies in [0.3, 1].
        const double solid_angle = 2 * kPi * (1 - std::cos(a.half_angle_rad));
        const double e = between(0.3, 1.0);
        a.radiance = e * kPi / solid_angle;
        strongest = std::max(strongest, e);
        l.areas.push_back(a);
      }
      const double ambient = between(options.min_ambient, options.max_ambient) * strongest;
      // Split between a sky (from above the image plane) and all-round ambient.
      const double split = uniform(rng);
      l.sky = split * ambient;
      l.ambient = (1 - split) * ambient;
    } else {
      l.sh.assign(9, 0.0);
      l.sh[0] = 1.0 / 0.282095;  // irradiance 1 from the constant band
      for (std::size_t k = 1; k < 9; ++k)
        l.sh[k] = options.sh_variation * l.sh[0] * gauss(rng) * (k < 4 ? 1.0 : 0.6);
      // Keep the radiance physical enough that the irradiance stays positive
      // over the sphere: raise the constant band until it does.
      double lowest = 1e300;
      for (const Vec3& d : cap_samples(kPi, 400)) lowest = std::min(lowest, l.irradiance(d));
      if (lowest < 0.05) l.sh[0] += (0.05 - lowest) / 0.282095;
    }
    out.push_back(std::move(l));
  }
  return out;
}

cv::Mat render_natural(const cv::Mat& normals, const cv::Mat& albedo, const cv::Mat& mask,
                       const NaturalLighting& lighting, int threads) {
  if (normals.type() != CV_32FC3 || albedo.type() != CV_32FC1 || mask.type() != CV_8UC1 ||
      albedo.size() != normals.size() || mask.size() != normals.size())
    fail("render_natural: normals CV_32FC3, albedo CV_32FC1 and mask CV_8UC1 of one size are needed");
  cv::Mat out = cv::Mat::zeros(normals.size(), CV_64FC1);
  parallel_for(normals.rows, threads, [&](int r) {
    for (int c = 0; c < normals.cols; ++c) {
      if (!mask.at<std::uint8_t>(r, c)) continue;
      const cv::Vec3f n = normals.at<cv::Vec3f>(r, c);
      const Vec3 nn = Vec3(n[0], n[1], n[2]).normalized();
      out.at<double>(r, c) = albedo.at<float>(r, c) * lighting.irradiance(nn);
    }
  });
  return out;
}

}  // namespace lightstage::sim
