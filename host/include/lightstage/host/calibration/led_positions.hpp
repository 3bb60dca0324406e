#pragma once
// LED positions from mirror reflections. Each highlight gives a ray from the
// sphere point toward the LED; rays from two or more sphere positions meet
// at the LED (least squares: the point nearest to all rays, with the RMS
// distance to them as its residual). That point starts a maximum-likelihood
// refinement: the LED position whose predicted highlights (the mirror point
// of a point light on each sphere, projected) best match the measured ones,
// each weighted by its covariance — so a grazing, elongated or faint
// highlight counts for what it is worth, and the fit's covariance says how
// well the position is known (the rays' conditioning included). With one
// sphere position, a known dome radius stands in for the second ray: the LED
// is where the ray meets the dome. Measured positions are then fitted to the
// rig's nominal layout — a rigid transform plus a per-LED correction — as a
// sanity check.

#include "lightstage/common/geometry.hpp"
#include "lightstage/host/calibration/mirror_sphere.hpp"

#include <nlohmann/json.hpp>

#include <optional>
#include <vector>

namespace lightstage::calibration {

struct Ray {
  Vec3 origin;
  Vec3 direction;  // unit
};

struct Triangulation {
  Vec3 position_mm = Vec3::Zero();
  double rms_mm = 0;  // RMS distance from the rays
  double max_mm = 0;  // largest distance from a ray
  // Smallest / largest eigenvalue of Σ(I − d dᵀ): near 0 when the rays are
  // (nearly) parallel and the depth along them is undetermined.
  double conditioning = 0;
  std::size_t rays = 0;
};

// The point nearest to all `rays` (at least 2). nullopt when they are parallel
// (conditioning below `min_conditioning`).
std::optional<Triangulation> triangulate(const std::vector<Ray>& rays, double min_conditioning = 1e-6);

// Where `ray` leaves the sphere of `radius_mm` around `centre_mm` (the ray
// starts inside it); nullopt when it starts outside and misses.
std::optional<Vec3> intersect_dome(const Ray& ray, const Vec3& centre_mm, double radius_mm);

// The image point where `sphere` mirrors a point light at `led_mm`: the
// sphere point whose mirror direction of the viewing ray passes through the
// LED, projected. nullopt when that point is hidden from the camera or the
// LED is not outside the sphere.
std::optional<Vec2> predict_highlight(const MirrorSphere& sphere, const CameraGeometry& camera,
                                      const Vec3& led_mm);

// One measured highlight of an LED: the sphere it was seen on, its image
// point and that point's covariance (px², positive definite).
struct HighlightObservation {
  MirrorSphere sphere;
  Vec2 centre_px = Vec2::Zero();
  Eigen::Matrix2d covariance_px = Eigen::Matrix2d::Identity();
};

struct LedFit {
  Vec3 position_mm = Vec3::Zero();
  // Of the position (mm²), from the highlights' covariances, linearised at the solution.
  Eigen::Matrix3d covariance_mm2 = Eigen::Matrix3d::Zero();
  double sigma_mm = 0;  // standard deviation along the worst-determined direction
  double rms_px = 0;    // RMS distance between measured and predicted highlights
  double chi2 = 0;      // Σ of the squared covariance-normalised highlight misfits
  int iterations = 0;
};

// Maximum-likelihood LED position from at least two highlights on spheres at
// different positions, starting at `start_mm` (e.g. the rays' triangulation).
// nullopt when the highlights do not determine the position (one sphere
// position, or rays too close to parallel) or a prediction fails.
std::optional<LedFit> refine_led_position(const std::vector<HighlightObservation>& observations,
                                          const CameraGeometry& camera, const Vec3& start_mm);

struct NominalFit {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // measured ≈ R · nominal + t
  Vec3 translation = Vec3::Zero();
  std::vector<Vec3> corrections;  // per LED: measured − (R · nominal + t)
  double rms_mm = 0;              // of the corrections
  double max_mm = 0;
  double rotation_deg = 0;  // angle of R

  nlohmann::json to_json() const;
};

// Rigid (no scale) least-squares fit of `nominal` onto `measured` (same
// order, at least 3 non-collinear points). Throws InputError otherwise.
NominalFit fit_to_nominal(const std::vector<Vec3>& nominal, const std::vector<Vec3>& measured);

}  // namespace lightstage::calibration
