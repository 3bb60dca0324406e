#include "lightstage/sim/renderer.hpp"

#include "lightstage/common/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lightstage::sim {
namespace {

constexpr int kSupersample = 16;  // the fewest subsamples per axis near a highlight

double angle(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

Vec3 mirror(const Vec3& n, const Vec3& v) { return 2.0 * n.dot(v) * n - v; }

}  // namespace

Renderer::Renderer(const Scene& scene, const Camera& camera, const Vec3& object_position_mm, LightModel model,
                   int threads)
    : scene_(scene), camera_(camera), object_position_(object_position_mm), model_(model), threads_(threads) {
  const int w = camera_.width, h = camera_.height;
  pixels_.resize(static_cast<std::size_t>(w) * h);
  mask_ = cv::Mat::zeros(h, w, CV_8UC1);
  truth_.normals = cv::Mat::zeros(h, w, CV_32FC3);
  truth_.depth = cv::Mat::zeros(h, w, CV_32FC1);
  if (scene_.material.colour) tint_ = cv::Mat::zeros(h, w, CV_64FC3);
  const bool mirror_material = scene_.material.is_mirror();
  parallel_for(h, threads_, [&](int r) {
    for (int c = 0; c < w; ++c) {
      Pixel& px = pixels_[static_cast<std::size_t>(r) * w + c];
      const auto hit = trace(c + 0.5, r + 0.5, &px.view);
      if (!hit) continue;
      px.hit = true;
      px.point = hit->point;
      px.normal = hit->normal;
      px.albedo = scene_.material.albedo.eval(hit->point.x(), hit->point.y());
      if (!tint_.empty()) {
        const Vec3 rgb = scene_.material.colour->eval(hit->point.x(), hit->point.y());
        tint_.at<cv::Vec3d>(r, c) = cv::Vec3d(rgb.z(), rgb.y(), rgb.x());  // BGR
      }
      mask_.at<std::uint8_t>(r, c) = 255;
      truth_.normals.at<cv::Vec3f>(r, c) =
          cv::Vec3f(static_cast<float>(hit->normal.x()), static_cast<float>(hit->normal.y()),
                    static_cast<float>(hit->normal.z()));
      truth_.depth.at<float>(r, c) = static_cast<float>(hit->point.z() + object_position_.z());
      if (mirror_material) {
        px.reflect = mirror(px.normal, px.view);
        // At the limb some corners miss the object; twice the spread to the
        // others stands in for them.
        bool missed = false;
        for (const auto& [du, dv] : {std::pair{0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}, {1.0, 1.0}}) {
          Vec3 corner_view;
          const auto corner = trace(c + du, r + dv, &corner_view);
          if (corner) {
            px.spread = std::max(px.spread, angle(px.reflect, mirror(corner->normal, corner_view)));
          } else {
            missed = true;
          }
        }
        if (missed) px.spread = px.spread > 0 ? std::min(kPi, 2 * px.spread) : kPi;
      }
    }
  });
  if (mirror_material && scene_.environment_radiance > 0) coverage_ = silhouette_coverage();
}

cv::Mat Renderer::silhouette_coverage() const {
  const int w = camera_.width, h = camera_.height;
  constexpr int kSamples = 8;
  cv::Mat corners(h + 1, w + 1, CV_8UC1, cv::Scalar::all(0));
  parallel_for(h + 1, threads_, [&](int r) {
    for (int c = 0; c <= w; ++c) {
      Vec3 view;
      corners.at<std::uint8_t>(r, c) = trace(c, r, &view) ? 1 : 0;
    }
  });
  cv::Mat coverage(h, w, CV_64FC1, cv::Scalar::all(0));
  parallel_for(h, threads_, [&](int r) {
    for (int c = 0; c < w; ++c) {
      const int hits = corners.at<std::uint8_t>(r, c) + corners.at<std::uint8_t>(r, c + 1) +
                       corners.at<std::uint8_t>(r + 1, c) + corners.at<std::uint8_t>(r + 1, c + 1) +
                       (mask_.at<std::uint8_t>(r, c) != 0 ? 1 : 0);
      if (hits == 0) continue;
      if (hits == 5) {
        coverage.at<double>(r, c) = 1.0;
        continue;
      }
      int inside = 0;
      for (int j = 0; j < kSamples; ++j) {
        for (int i = 0; i < kSamples; ++i) {
          Vec3 view;
          if (trace(c + (i + 0.5) / kSamples, r + (j + 0.5) / kSamples, &view)) ++inside;
        }
      }
      coverage.at<double>(r, c) = static_cast<double>(inside) / (kSamples * kSamples);
    }
  });
  return coverage;
}

std::optional<Hit> Renderer::trace(double u, double v, Vec3* view) const {
  Vec3 origin, dir;
  camera_.ray(u, v, &origin, &dir);
  *view = -dir;
  return scene_.shape->intersect(origin - object_position_, dir);
}

void Renderer::light_at(const Vec3& p, const Vec3& x, Vec3* dir, double* irradiance, double* distance) const {
  if (model_ == LightModel::kDistant) {
    *dir = p.normalized();
    *irradiance = 1.0;
    *distance = std::numeric_limits<double>::max();
    return;
  }
  const Vec3 d = p - x;
  const double dist2 = d.squaredNorm();
  *distance = std::sqrt(dist2);
  *dir = d / *distance;
  *irradiance = p.squaredNorm() / dist2;
}

Renderer::Splat Renderer::mirror_coverage(int row, int col, const Pixel& px, const Vec3& led) const {
  auto led_radius_rad = [&](double distance) {
    const double d = model_ == LightModel::kDistant ? led.norm() : distance;
    return std::asin(std::min(1.0, scene_.led_radius_mm / d));
  };
  Splat out{col + 0.5, row + 0.5, 0.0};
  Vec3 dir;
  double irradiance, distance;
  light_at(led, px.point, &dir, &irradiance, &distance);
  // Subsamples fine enough that the disk spans several of them across (the
  // pixel spans `width` radians of reflected direction, about twice the
  // normal's change); each counts the fraction of a ramp one subsample wide
  // that lies inside the disk, which anti-aliases the edge.
  const double width = px.spread * std::sqrt(2.0);
  const double alpha = led_radius_rad(distance);
  const double wanted = std::ceil(6.0 * width / std::max(alpha, 1e-9));
  const int n = static_cast<int>(std::clamp(wanted, static_cast<double>(kSupersample), 64.0));
  const double sub = std::max(width / n, 1e-12);
  if (angle(px.reflect, dir) > alpha + px.spread + sub) return out;
  double inside = 0, su = 0, sv = 0;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double u = col + (i + 0.5) / n, v = row + (j + 0.5) / n;
      Vec3 view;
      const auto hit = trace(u, v, &view);
      if (!hit) continue;
      light_at(led, hit->point, &dir, &irradiance, &distance);
      const double off = led_radius_rad(distance) - angle(mirror(hit->normal, view), dir);
      const double w = std::clamp(0.5 + off / sub, 0.0, 1.0);
      inside += w;
      su += w * u;
      sv += w * v;
    }
  }
  if (inside > 0) out = Splat{su / inside, sv / inside, inside / (static_cast<double>(n) * n)};
  return out;
}

void Renderer::add_mirror(const Vec3& led, double scale, cv::Mat& out) const {
  const int w = camera_.width, h = camera_.height;
  std::vector<std::vector<Splat>> rows(static_cast<std::size_t>(h));
  parallel_for(h, threads_, [&](int r) {
    for (int c = 0; c < w; ++c) {
      const Pixel& px = pixels_[static_cast<std::size_t>(r) * w + c];
      if (!px.hit) continue;
      const Splat s = mirror_coverage(r, c, px, led);
      if (s.weight > 0) rows[static_cast<std::size_t>(r)].push_back(s);
    }
  });
  // The lens blur: each pixel's part of the highlight, as a point at its
  // centroid, spread by a Gaussian integrated over the receiving pixels.
  const double sigma = scene_.highlight_blur_px;
  for (const auto& row : rows) {
    for (const Splat& s : row) {
      if (sigma <= 0) {
        out.at<double>(static_cast<int>(s.v), static_cast<int>(s.u)) += scale * s.weight;
        continue;
      }
      const int reach = static_cast<int>(std::ceil(4 * sigma));
      const int c0 = static_cast<int>(s.u), r0 = static_cast<int>(s.v);
      auto weights = [&](double centre, int first) {
        std::vector<double> wts;
        double total = 0;
        for (int k = 0; k <= 2 * reach; ++k) {
          const double lo = first + k - centre, hi = lo + 1;
          wts.push_back(0.5 *
                        (std::erf(hi / (sigma * std::sqrt(2.0))) - std::erf(lo / (sigma * std::sqrt(2.0)))));
          total += wts.back();
        }
        for (double& x : wts) x /= total;
        return wts;
      };
      const auto wx = weights(s.u, c0 - reach), wy = weights(s.v, r0 - reach);
      for (int j = 0; j <= 2 * reach; ++j) {
        const int r = r0 - reach + j;
        if (r < 0 || r >= h) continue;
        auto* dst = out.ptr<double>(r);
        for (int i = 0; i <= 2 * reach; ++i) {
          const int c = c0 - reach + i;
          if (c >= 0 && c < w)
            dst[c] += scale * s.weight * wx[static_cast<std::size_t>(i)] * wy[static_cast<std::size_t>(j)];
        }
      }
    }
  }
}

cv::Mat Renderer::render(const std::vector<LightSource>& lights) const {
  cv::Mat out;
  shade(lights, &out, nullptr);
  return out;
}

void Renderer::render_parts(const std::vector<LightSource>& lights, cv::Mat* diffuse,
                            cv::Mat* specular) const {
  shade(lights, diffuse, specular);
}

cv::Mat Renderer::render_colour(const std::vector<LightSource>& lights) const {
  cv::Mat diffuse, specular;
  shade(lights, &diffuse, &specular);
  const int w = camera_.width, h = camera_.height;
  cv::Mat out(h, w, CV_64FC3);
  for (int r = 0; r < h; ++r) {
    const double* d = diffuse.ptr<double>(r);
    const double* s = specular.ptr<double>(r);
    const auto* t = tint_.empty() ? nullptr : tint_.ptr<cv::Vec3d>(r);
    auto* o = out.ptr<cv::Vec3d>(r);
    for (int c = 0; c < w; ++c) {
      for (int k = 0; k < 3; ++k) o[c][k] = (t ? d[c] * t[c][k] : d[c]) + s[c];
    }
  }
  return out;
}

void Renderer::shade(const std::vector<LightSource>& lights, cv::Mat* out_mat, cv::Mat* specular_mat) const {
  const int w = camera_.width, h = camera_.height;
  *out_mat = cv::Mat::zeros(h, w, CV_64FC1);
  cv::Mat& out = *out_mat;
  const bool split = specular_mat != nullptr;
  if (split) *specular_mat = cv::Mat::zeros(h, w, CV_64FC1);
  cv::Mat& white = split ? *specular_mat : out;  // where the untinted part goes
  const Material& m = scene_.material;
  const bool mirror_material = m.is_mirror();
  const bool has_diffuse = m.diffuse && m.kd != 0;
  const bool has_specular = m.specular && !mirror_material && m.ks != 0;
  std::vector<Vec3> leds;
  for (const auto& light : lights) leds.push_back(light.position_mm - object_position_);
  if (has_diffuse || has_specular) {
    parallel_for(h, threads_, [&](int r) {
      auto* row = out.ptr<double>(r);
      auto* spec_row = split ? specular_mat->ptr<double>(r) : nullptr;
      for (int c = 0; c < w; ++c) {
        const Pixel& px = pixels_[static_cast<std::size_t>(r) * w + c];
        if (!px.hit) continue;
        double sum = 0, spec_sum = 0;
        for (std::size_t k = 0; k < lights.size(); ++k) {
          if (lights[k].intensity == 0) continue;
          Vec3 l;
          double e, distance;
          light_at(leds[k], px.point, &l, &e, &distance);
          const double cos_l = px.normal.dot(l);
          if (cos_l <= 0) continue;
          const double fd = has_diffuse ? m.kd * px.albedo * m.diffuse->eval(px.normal, l, px.view) : 0.0;
          const double fs = has_specular ? m.ks * m.specular->eval(px.normal, l, px.view) : 0.0;
          const double f = fd + fs;
          if (f > 0 && !(scene_.cast_shadows && scene_.shape->occluded(px.point, l, distance))) {
            if (split) {
              sum += lights[k].intensity * e * fd * cos_l;
              spec_sum += lights[k].intensity * e * fs * cos_l;
            } else {
              sum += lights[k].intensity * e * f * cos_l;
            }
          }
        }
        row[c] = sum;
        if (split) spec_row[c] = spec_sum;
      }
    });
  }
  if (mirror_material && !coverage_.empty()) {
    double on = 0;
    for (const auto& light : lights) on += light.intensity;
    white += coverage_ * (on * scene_.environment_radiance * m.mirror_reflectance());
  }
  if (mirror_material) {
    for (std::size_t k = 0; k < lights.size(); ++k) {
      if (lights[k].intensity == 0) continue;
      add_mirror(leds[k], lights[k].intensity * scene_.led_radiance * m.mirror_reflectance(), white);
    }
  }
}

cv::Mat Renderer::tint_map() const {
  cv::Mat out = cv::Mat::zeros(camera_.height, camera_.width, CV_32FC3);
  for (int r = 0; r < camera_.height; ++r)
    for (int c = 0; c < camera_.width; ++c) {
      if (!pixels_[static_cast<std::size_t>(r) * camera_.width + c].hit) continue;
      out.at<cv::Vec3f>(r, c) = tint_.empty() ? cv::Vec3f(1, 1, 1) : cv::Vec3f(tint_.at<cv::Vec3d>(r, c));
    }
  return out;
}

cv::Mat Renderer::albedo_map() const {
  cv::Mat out = cv::Mat::zeros(camera_.height, camera_.width, CV_32FC1);
  for (int r = 0; r < camera_.height; ++r)
    for (int c = 0; c < camera_.width; ++c) {
      const Pixel& px = pixels_[static_cast<std::size_t>(r) * camera_.width + c];
      if (px.hit) out.at<float>(r, c) = static_cast<float>(px.albedo);
    }
  return out;
}

}  // namespace lightstage::sim
