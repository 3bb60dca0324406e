#pragma once
// The object's geometry in the object frame (dome axes, origin at the rig's
// object position, millimetres): exact intersections, analytic normals and
// cast-shadow queries. Spheres are convex, so they only have attached
// shadows; height fields z = h(x, y) march shadow rays through the surface.

#include "lightstage/common/geometry.hpp"

#include <nlohmann/json.hpp>

#include <memory>
#include <optional>
#include <utility>
#include <vector>

namespace lightstage::sim {

struct Hit {
  Vec3 point;   // object frame, mm
  Vec3 normal;  // unit, outward
};

class Shape {
 public:
  virtual ~Shape() = default;
  // First intersection of origin + t·dir, t > 0 (dir unit).
  virtual std::optional<Hit> intersect(const Vec3& origin, const Vec3& dir) const = 0;
  // Whether the ray from surface point p toward unit `dir` meets the surface
  // again within max_distance (a cast shadow).
  virtual bool occluded(const Vec3& p, const Vec3& dir, double max_distance) const = 0;
  virtual nlohmann::json describe() const = 0;
};

class Sphere final : public Shape {
 public:
  Sphere(const Vec3& center_mm, double radius_mm);
  std::optional<Hit> intersect(const Vec3& origin, const Vec3& dir) const override;
  bool occluded(const Vec3&, const Vec3&, double) const override { return false; }
  nlohmann::json describe() const override;

 private:
  Vec3 center_;
  double radius_;
};

// A surface z = h(x, y) >= 0 with its exact gradient.
class HeightFunction {
 public:
  virtual ~HeightFunction() = default;
  // h(x, y); writes (dh/dx, dh/dy) to *gradient when given.
  virtual double height(double x, double y, Vec2* gradient) const = 0;
  // Half-extent of the square around the origin outside which h = 0.
  virtual double half_extent_mm() const = 0;
  virtual nlohmann::json describe() const = 0;
};

// Sum of Gaussian bumps a·exp(-|p - c|² / (2 s²)).
class GaussianBumps final : public HeightFunction {
 public:
  struct Bump {
    Vec2 center_mm;
    double height_mm;
    double sigma_mm;
  };
  GaussianBumps(std::vector<Bump> bumps, double half_extent_mm);
  double height(double x, double y, Vec2* gradient) const override;
  double half_extent_mm() const override { return half_extent_; }
  nlohmann::json describe() const override;

 private:
  std::vector<Bump> bumps_;
  double half_extent_;
};

// Raised letters, a ring and a two-level step with small smoothstep bevels:
// sharp-ish detail. The layout is fixed and scaled to `size_mm`.
class Relief final : public HeightFunction {
 public:
  Relief(double size_mm, double height_mm, double bevel_mm);
  double height(double x, double y, Vec2* gradient) const override;
  double half_extent_mm() const override { return size_ / 2; }
  nlohmann::json describe() const override;

 private:
  struct Feature {
    bool ring;
    Vec2 center;
    Vec2 half_size;  // box: half width/height; ring: (radius, half width)
    double height;
  };
  double size_, height_, bevel_;
  std::vector<Feature> features_;
};

// A bunny-like blob: ellipsoidal body, head, ears, tail and feet merged by a
// smooth maximum of squared heights (so the sides are steep, nearly vertical
// at the silhouette), creases where parts meet and dents for eyes: concave
// regions and self-shadowing. Scaled to `size_mm`.
class Blob final : public HeightFunction {
 public:
  explicit Blob(double size_mm);
  double height(double x, double y, Vec2* gradient) const override;
  double half_extent_mm() const override { return size_ / 2; }
  nlohmann::json describe() const override;

 private:
  struct Part {
    Vec2 center, radii;
    double height;
  };
  double size_, blend_;
  std::vector<Part> parts_;
  std::vector<GaussianBumps::Bump> dents_;
};

// A height field over a base plane z = 0, visible inside its footprint only
// (outside is background, masked out).
class HeightField final : public Shape {
 public:
  enum class Footprint {
    kSquare,   // |x|, |y| <= size/2
    kDisk,     // |p| <= size/2
    kSupport,  // where h > min_height_mm (the object stands alone)
  };
  static constexpr double kMinHeightMm = 0.05;

  HeightField(std::shared_ptr<const HeightFunction> function, Footprint footprint, double footprint_size_mm);
  std::optional<Hit> intersect(const Vec3& origin, const Vec3& dir) const override;
  bool occluded(const Vec3& p, const Vec3& dir, double max_distance) const override;
  nlohmann::json describe() const override;

  bool inside(double x, double y, double h) const;
  const HeightFunction& function() const { return *function_; }

 private:
  // Marches origin + t·dir from t0; returns (last t above, first t under) the
  // surface inside the footprint.
  std::optional<std::pair<double, double>> march(const Vec3& origin, const Vec3& dir, double t0,
                                                 double t_max) const;
  std::size_t tile(double x, double y) const;

  std::shared_ptr<const HeightFunction> function_;
  Footprint footprint_;
  double footprint_size_;
  double half_;       // half-extent of the marched square
  double spacing_;    // sample spacing of the acceleration grid, mm
  int tile_samples_;  // samples per tile side
  int tiles_;         // tiles per side
  double max_height_ = 0;
  std::vector<float> tile_max_;    // dilated (3×3 tiles) maximum height plus a margin
  std::vector<float> tile_slope_;  // dilated maximum slope |dh/dxy| with a margin
};

}  // namespace lightstage::sim
