#include "lightstage/sim/shape.hpp"

#include "lightstage/common/error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lightstage::sim {
namespace {

// Index of the cell holding `value` on a grid of `count` cells, clamped; safe
// for NaN and huge values.
int clamped_index(double value, int count) {
  if (!(value >= 0)) return 0;
  if (value >= count) return count - 1;
  return static_cast<int>(value);
}

Vec3 normal_from_gradient(const Vec2& g) { return Vec3(-g.x(), -g.y(), 1.0).normalized(); }

// Polynomial smooth maximum with blend width k; d/da = w, d/db = 1 - w.
double smooth_max(double a, double b, double k, double* w) {
  const double h = std::clamp(0.5 + 0.5 * (a - b) / k, 0.0, 1.0);
  *w = h;
  return b + (a - b) * h + k * h * (1.0 - h);
}

}  // namespace

// ---------------------------------------------------------------- Sphere

Sphere::Sphere(const Vec3& center_mm, double radius_mm) : center_(center_mm), radius_(radius_mm) {
  if (!(radius_mm > 0)) fail("sphere: radius_mm must be positive, got {}", radius_mm);
}

std::optional<Hit> Sphere::intersect(const Vec3& origin, const Vec3& dir) const {
  const Vec3 oc = origin - center_;
  const double b = oc.dot(dir);
  const double c = oc.squaredNorm() - radius_ * radius_;
  const double disc = b * b - c;
  if (disc < 0) return std::nullopt;
  const double s = std::sqrt(disc);
  double t = -b - s;
  if (t <= 0) t = -b + s;
  if (t <= 0) return std::nullopt;
  const Vec3 p = origin + t * dir;
  return Hit{p, (p - center_).normalized()};
}

nlohmann::json Sphere::describe() const {
  return {{"type", "sphere"}, {"radius_mm", radius_}, {"center_mm", {center_.x(), center_.y(), center_.z()}}};
}

// ---------------------------------------------------------------- GaussianBumps

GaussianBumps::GaussianBumps(std::vector<Bump> bumps, double half_extent_mm)
    : bumps_(std::move(bumps)), half_extent_(half_extent_mm) {
  for (const auto& b : bumps_) {
    if (!(b.sigma_mm > 0)) fail("bumps: sigma_mm must be positive, got {}", b.sigma_mm);
    if (!(b.height_mm >= 0)) fail("bumps: height_mm must not be negative, got {}", b.height_mm);
  }
}

double GaussianBumps::height(double x, double y, Vec2* gradient) const {
  double h = 0;
  Vec2 g = Vec2::Zero();
  for (const auto& b : bumps_) {
    const double dx = x - b.center_mm.x();
    const double dy = y - b.center_mm.y();
    const double s2 = b.sigma_mm * b.sigma_mm;
    const double r2 = dx * dx + dy * dy;
    if (r2 > 100 * s2) continue;  // below 2e-22 of the peak
    const double e = b.height_mm * std::exp(-r2 / (2 * s2));
    h += e;
    g += Vec2(-dx / s2 * e, -dy / s2 * e);
  }
  if (gradient) *gradient = g;
  return h;
}

nlohmann::json GaussianBumps::describe() const {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& b : bumps_) {
    list.push_back({{"center_mm", {b.center_mm.x(), b.center_mm.y()}},
                    {"height_mm", b.height_mm},
                    {"sigma_mm", b.sigma_mm}});
  }
  return {{"type", "bumps"}, {"bumps", list}};
}

// ---------------------------------------------------------------- Relief

Relief::Relief(double size_mm, double height_mm, double bevel_mm)
    : size_(size_mm), height_(height_mm), bevel_(bevel_mm) {
  if (!(size_mm > 0)) fail("relief: size_mm must be positive, got {}", size_mm);
  if (!(height_mm > 0)) fail("relief: height_mm must be positive, got {}", height_mm);
  if (!(bevel_mm > 0)) fail("relief: bevel_mm must be positive, got {}", bevel_mm);
  const double u = size_mm / 100.0;  // layout units: the square is [-50, 50]²
  auto box = [&](double cx, double cy, double hx, double hy, double level) {
    features_.push_back({false, Vec2(cx, cy) * u, Vec2(hx, hy) * u, level * height_mm});
  };
  // A two-level step.
  box(-25, -25, 20, 18, 0.5);
  box(-25, -25, 10, 8, 1.0);
  // "L"
  box(-30, 22, 4, 16, 1.0);
  box(-22, 9, 12, 3.5, 1.0);
  // "S"
  box(12, 34, 12, 3.5, 1.0);
  box(3.5, 27, 3.5, 7, 1.0);
  box(12, 20, 12, 3.5, 1.0);
  box(20.5, 13, 3.5, 7, 1.0);
  box(12, 6, 12, 3.5, 1.0);
  // A ring.
  features_.push_back({true, Vec2(25, -25) * u, Vec2(14, 3) * u, height_mm});
}

double Relief::height(double x, double y, Vec2* gradient) const {
  double best = 0;
  Vec2 best_gradient = Vec2::Zero();
  for (const auto& f : features_) {
    const Vec2 p(x - f.center.x(), y - f.center.y());
    double sd;
    Vec2 sd_gradient;
    if (f.ring) {
      const double r = p.norm();
      const double d = r - f.half_size.x();
      sd = std::abs(d) - f.half_size.y();
      sd_gradient = r > 1e-12 ? Vec2(p / r * (d >= 0 ? 1.0 : -1.0)) : Vec2(1, 0);
    } else {
      const Vec2 q(std::abs(p.x()) - f.half_size.x(), std::abs(p.y()) - f.half_size.y());
      const Vec2 sign(p.x() >= 0 ? 1.0 : -1.0, p.y() >= 0 ? 1.0 : -1.0);
      if (q.x() > 0 || q.y() > 0) {
        const Vec2 out(std::max(q.x(), 0.0), std::max(q.y(), 0.0));
        sd = out.norm();
        sd_gradient = Vec2(out.x() * sign.x(), out.y() * sign.y()) / sd;
      } else {
        sd = std::max(q.x(), q.y());
        sd_gradient = q.x() > q.y() ? Vec2(sign.x(), 0) : Vec2(0, sign.y());
      }
    }
    // Smoothstep bevel from the edge (sd = 0) to bevel_ inside.
    const double t = std::clamp(-sd / bevel_, 0.0, 1.0);
    const double h = f.height * t * t * (3 - 2 * t);
    if (h > best) {
      best = h;
      best_gradient = f.height * 6 * t * (1 - t) * (-1.0 / bevel_) * sd_gradient;
    }
  }
  if (gradient) *gradient = best_gradient;
  return best;
}

nlohmann::json Relief::describe() const {
  return {{"type", "relief"}, {"size_mm", size_}, {"height_mm", height_}, {"bevel_mm", bevel_}};
}

// ---------------------------------------------------------------- Blob

Blob::Blob(double size_mm) : size_(size_mm) {
  if (!(size_mm > 0)) fail("blob: size_mm must be positive, got {}", size_mm);
  const double s = size_mm;
  auto part = [&](double cx, double cy, double rx, double ry, double h) {
    parts_.push_back({Vec2(cx, cy) * s, Vec2(rx, ry) * s, h * s});
  };
  part(-0.08, -0.10, 0.30, 0.24, 0.30);  // body
  part(0.20, 0.12, 0.14, 0.13, 0.24);    // head
  part(0.13, 0.33, 0.045, 0.14, 0.20);   // ears
  part(0.27, 0.33, 0.045, 0.13, 0.18);
  part(-0.38, -0.02, 0.07, 0.07, 0.12);  // tail
  part(0.08, -0.33, 0.13, 0.05, 0.08);   // feet
  part(-0.20, -0.33, 0.10, 0.05, 0.07);
  blend_ = 0.01 * s * s;
  dents_.push_back({Vec2(0.26, 0.16) * s, 0.02 * s, 0.018 * s});   // eye
  dents_.push_back({Vec2(-0.05, -0.05) * s, 0.03 * s, 0.05 * s});  // a hollow in the back
}

double Blob::height(double x, double y, Vec2* gradient) const {
  // F = smooth max over parts of h_i² (1 - q_i); the surface is sqrt(F).
  double f = 0;
  Vec2 df = Vec2::Zero();
  bool first = true;
  for (const auto& p : parts_) {
    const double ux = (x - p.center.x()) / p.radii.x();
    const double uy = (y - p.center.y()) / p.radii.y();
    const double h2 = p.height * p.height;
    const double fi = h2 * (1 - ux * ux - uy * uy);
    const Vec2 dfi(-2 * h2 * ux / p.radii.x(), -2 * h2 * uy / p.radii.y());
    if (first) {
      f = fi;
      df = dfi;
      first = false;
    } else {
      double w;
      f = smooth_max(fi, f, blend_, &w);
      df = w * dfi + (1 - w) * df;
    }
  }
  const double f_min = 1e-12 * size_ * size_;
  if (f <= f_min) {
    if (gradient) *gradient = Vec2::Zero();
    return 0;
  }
  const double root = std::sqrt(f);
  double h = root;
  Vec2 g = df / (2 * root);
  for (const auto& d : dents_) {
    const double dx = x - d.center_mm.x();
    const double dy = y - d.center_mm.y();
    const double s2 = d.sigma_mm * d.sigma_mm;
    const double e = d.height_mm * std::exp(-(dx * dx + dy * dy) / (2 * s2));
    h -= e;
    g -= Vec2(-dx / s2 * e, -dy / s2 * e);
  }
  if (h <= 0) {
    if (gradient) *gradient = Vec2::Zero();
    return 0;
  }
  if (gradient) *gradient = g;
  return h;
}

nlohmann::json Blob::describe() const { return {{"type", "blob"}, {"size_mm", size_}}; }

// ---------------------------------------------------------------- HeightField

HeightField::HeightField(std::shared_ptr<const HeightFunction> function, Footprint footprint,
                         double footprint_size_mm)
    : function_(std::move(function)), footprint_(footprint), footprint_size_(footprint_size_mm) {
  if (footprint != Footprint::kSupport && !(footprint_size_mm > 0)) {
    fail("height field: footprint size_mm must be positive, got {}", footprint_size_mm);
  }
  half_ =
      std::max(function_->half_extent_mm(), footprint == Footprint::kSupport ? 0.0 : footprint_size_mm / 2);
  tile_samples_ = 8;
  tiles_ = 32;
  const int samples = tile_samples_ * tiles_ + 1;
  spacing_ = 2 * half_ / (samples - 1);
  std::vector<double> grid(static_cast<std::size_t>(samples) * samples);
  auto at = [&](int i, int j) -> double& { return grid[static_cast<std::size_t>(j) * samples + i]; };
  for (int j = 0; j < samples; ++j) {
    for (int i = 0; i < samples; ++i) {
      at(i, j) = function_->height(-half_ + i * spacing_, -half_ + j * spacing_, nullptr);
      max_height_ = std::max(max_height_, at(i, j));
    }
  }
  // Per tile: the sampled maximum plus the largest jump between neighbouring
  // samples (what a peak between samples can add), then dilated over the 3×3
  // neighbouring tiles so a one-tile step from anywhere in a tile is safe.
  std::vector<float> raw(static_cast<std::size_t>(tiles_) * tiles_);
  std::vector<float> raw_slope(raw.size());
  double global_margin = 0;
  for (int tj = 0; tj < tiles_; ++tj) {
    for (int ti = 0; ti < tiles_; ++ti) {
      double m = 0, jump = 0;
      for (int j = tj * tile_samples_; j <= (tj + 1) * tile_samples_; ++j) {
        for (int i = ti * tile_samples_; i <= (ti + 1) * tile_samples_; ++i) {
          m = std::max(m, at(i, j));
          if (i + 1 < samples) jump = std::max(jump, std::abs(at(i + 1, j) - at(i, j)));
          if (j + 1 < samples) jump = std::max(jump, std::abs(at(i, j + 1) - at(i, j)));
        }
      }
      global_margin = std::max(global_margin, jump);
      raw[static_cast<std::size_t>(tj) * tiles_ + ti] = static_cast<float>(m + jump + 1e-3);
      raw_slope[static_cast<std::size_t>(tj) * tiles_ + ti] =
          static_cast<float>(1.5 * jump / spacing_ + 0.05);
    }
  }
  max_height_ += global_margin + 1e-3;
  tile_max_.assign(raw.size(), 0.0f);
  tile_slope_.assign(raw.size(), 0.0f);
  for (int tj = 0; tj < tiles_; ++tj) {
    for (int ti = 0; ti < tiles_; ++ti) {
      float m = 0, slope = 0;
      for (int dj = -1; dj <= 1; ++dj) {
        for (int di = -1; di <= 1; ++di) {
          const int i = std::clamp(ti + di, 0, tiles_ - 1);
          const int j = std::clamp(tj + dj, 0, tiles_ - 1);
          m = std::max(m, raw[static_cast<std::size_t>(j) * tiles_ + i]);
          slope = std::max(slope, raw_slope[static_cast<std::size_t>(j) * tiles_ + i]);
        }
      }
      tile_max_[static_cast<std::size_t>(tj) * tiles_ + ti] = m;
      tile_slope_[static_cast<std::size_t>(tj) * tiles_ + ti] = slope;
    }
  }
}

bool HeightField::inside(double x, double y, double h) const {
  switch (footprint_) {
    case Footprint::kSquare:
      return std::abs(x) <= footprint_size_ / 2 && std::abs(y) <= footprint_size_ / 2;
    case Footprint::kDisk:
      return x * x + y * y <= footprint_size_ * footprint_size_ / 4;
    case Footprint::kSupport:
      return h > kMinHeightMm;
  }
  return false;
}

std::size_t HeightField::tile(double x, double y) const {
  const double size = tile_samples_ * spacing_;
  const int i = clamped_index((x + half_) / size, tiles_);
  const int j = clamped_index((y + half_) / size, tiles_);
  return static_cast<std::size_t>(j) * tiles_ + i;
}

std::optional<std::pair<double, double>> HeightField::march(const Vec3& origin, const Vec3& dir, double t0,
                                                            double t_max) const {
  // Clip to the box [-half, half]² × [-1, max_height].
  double lo = t0, hi = t_max;
  const double box_lo[3] = {-half_, -half_, -1.0};
  const double box_hi[3] = {half_, half_, max_height_};
  for (int a = 0; a < 3; ++a) {
    if (std::abs(dir[a]) < 1e-15) {
      if (origin[a] < box_lo[a] || origin[a] > box_hi[a]) return std::nullopt;
      continue;
    }
    double ta = (box_lo[a] - origin[a]) / dir[a];
    double tb = (box_hi[a] - origin[a]) / dir[a];
    if (ta > tb) std::swap(ta, tb);
    lo = std::max(lo, ta);
    hi = std::min(hi, tb);
  }
  if (!(lo <= hi)) return std::nullopt;
  const double dxy = std::hypot(dir.x(), dir.y());
  const double fine = 0.5 * spacing_ / std::max(dxy, 0.5);
  const double skip = tile_samples_ * spacing_ / std::max(dxy, 1e-9);
  double previous = lo;
  for (double t = lo; t <= hi;) {
    const Vec3 q = origin + t * dir;
    const std::size_t k = tile(q.x(), q.y());
    const double z_low = dir.z() >= 0 ? q.z() : q.z() + dir.z() * skip;
    if (z_low > tile_max_[k]) {
      previous = t;
      t += skip;
      continue;
    }
    const double h = function_->height(q.x(), q.y(), nullptr);
    if (h > q.z() && inside(q.x(), q.y(), h)) return std::pair{previous, t};
    // Within a tile's reach the surface rises at most tile_slope_ per mm, so
    // the gap above it closes at most this fast per unit t: step safely.
    const double closing = tile_slope_[k] * dxy - dir.z();
    const double gap = q.z() - h;
    const double step = gap > 0 && closing > 0 ? gap / closing : (gap > 0 ? skip : fine);
    previous = t;
    t += std::clamp(step, fine, skip);
  }
  return std::nullopt;
}

std::optional<Hit> HeightField::intersect(const Vec3& origin, const Vec3& dir) const {
  Vec3 p;
  if (dir.x() == 0 && dir.y() == 0 && dir.z() < 0) {
    p = Vec3(origin.x(), origin.y(), function_->height(origin.x(), origin.y(), nullptr));
    if (p.z() > origin.z()) return std::nullopt;
  } else {
    const auto t = march(origin, dir, 0.0, std::numeric_limits<double>::max());
    if (!t) return std::nullopt;
    // Bisect between the last point above and the first below the surface.
    double lo = t->first, hi = t->second;
    for (int k = 0; k < 40; ++k) {
      const double mid = 0.5 * (lo + hi);
      const Vec3 q = origin + mid * dir;
      const double h = function_->height(q.x(), q.y(), nullptr);
      if (h > q.z() && inside(q.x(), q.y(), h)) {
        hi = mid;
      } else {
        lo = mid;
      }
    }
    p = origin + hi * dir;
  }
  Vec2 g;
  const double h = function_->height(p.x(), p.y(), &g);
  if (!inside(p.x(), p.y(), h)) return std::nullopt;
  p.z() = h;
  return Hit{p, normal_from_gradient(g)};
}

bool HeightField::occluded(const Vec3& p, const Vec3& dir, double max_distance) const {
  return march(p, dir, 1e-3, max_distance).has_value();
}

nlohmann::json HeightField::describe() const {
  nlohmann::json j = function_->describe();
  const char* names[] = {"square", "disk", "support"};
  j["footprint"] = {{"shape", names[static_cast<int>(footprint_)]}};
  if (footprint_ != Footprint::kSupport) j["footprint"]["size_mm"] = footprint_size_;
  return j;
}

}  // namespace lightstage::sim
