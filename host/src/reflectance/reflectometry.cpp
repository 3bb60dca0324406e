#include "lightstage/host/reflectance/reflectometry.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/reflectance/bipolynomial_model.hpp"
#include "lightstage/host/solvers/pixel_observations.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

namespace lightstage {

void SampleOptions::check() const {
  if (!(std::isfinite(shadow_threshold) && shadow_threshold >= 0))
    fail("--shadow-threshold: must be finite and >= 0, got {}", shadow_threshold);
  if (!(t_low > 0 && t_low <= 1)) fail("--t-low: must be in (0, 1], got {}", t_low);
  if (max_samples < 16) fail("max_samples: must be at least 16, got {}", max_samples);
}

nlohmann::json ReflectanceFit::to_json() const {
  return {{"model", model},
          {"parameters", std::vector<double>(parameters.data(), parameters.data() + parameters.size())},
          {"rmse", rmse},
          {"mae", mae},
          {"relative_rmse", relative_rmse}};
}

ReflectanceSamples collect_samples(const Observations& observations, const cv::Mat& normals,
                                   const SampleOptions& options) {
  options.check();
  check_observations(observations, "reflectance");
  if (normals.type() != CV_32FC3 || normals.size() != observations.size)
    fail("reflectance: normals must be a {}x{} 3-channel float map", observations.size.width,
         observations.size.height);
  ReflectanceSamples all;
  PixelObservations pixel;
  std::vector<Eigen::Index> kept;
  for (std::size_t p = 0; p < observations.pixel_count(); ++p) {
    const cv::Vec3f v = normals.at<cv::Vec3f>(observations.pixels[p]);
    const Vec3 n(v[0], v[1], v[2]);
    if (!(n.norm() > 0.5)) continue;
    load_pixel(observations, p, options.drop_saturated, pixel);
    kept.clear();
    for (Eigen::Index j = 0; j < pixel.count(); ++j) {
      if (pixel.usable[static_cast<std::size_t>(j)] && pixel.values(j) > options.shadow_threshold)
        kept.push_back(j);
    }
    if (options.t_low < 1) {
      std::sort(kept.begin(), kept.end(),
                [&](Eigen::Index a, Eigen::Index b) { return pixel.values(a) < pixel.values(b); });
      kept.resize(
          static_cast<std::size_t>(std::ceil(options.t_low * static_cast<double>(kept.size()) - 1e-9)));
    }
    for (const Eigen::Index j : kept) {
      all.normals.push_back(n.normalized());
      all.lights.push_back(pixel.lights.row(j).transpose());
      all.values.push_back(pixel.values(j));
    }
  }
  if (all.size() <= options.max_samples) return all;
  ReflectanceSamples thinned;
  const double stride = static_cast<double>(all.size()) / static_cast<double>(options.max_samples);
  for (std::size_t k = 0; k < options.max_samples; ++k) {
    const auto i = static_cast<std::size_t>(static_cast<double>(k) * stride);
    thinned.normals.push_back(all.normals[i]);
    thinned.lights.push_back(all.lights[i]);
    thinned.values.push_back(all.values[i]);
  }
  return thinned;
}

namespace {

void score(const ReflectanceSamples& s, const std::vector<double>& predicted, ReflectanceFit& fit) {
  double squared = 0, absolute = 0, sum = 0;
  for (std::size_t k = 0; k < s.size(); ++k) {
    const double r = predicted[k] - s.values[k];
    squared += r * r;
    absolute += std::abs(r);
    sum += s.values[k];
  }
  const double count = static_cast<double>(std::max<std::size_t>(1, s.size()));
  fit.rmse = std::sqrt(squared / count);
  fit.mae = absolute / count;
  fit.relative_rmse = sum > 0 ? fit.rmse / (sum / count) : 0;
}

void require_samples(const ReflectanceSamples& s, std::size_t needed, const char* model) {
  if (s.size() < needed)
    fail(
        "reflectance: {} needs at least {} samples, the stack gave {} (check the mask, normals and shadow "
        "threshold)",
        model, needed, s.size());
}

}  // namespace

ReflectanceFit fit_lambert(const ReflectanceSamples& s) {
  require_samples(s, 1, "lambert");
  double num = 0, den = 0;
  std::vector<double> shade(s.size());
  for (std::size_t k = 0; k < s.size(); ++k) {
    shade[k] = std::max(s.normals[k].dot(s.lights[k]), 0.0);
    num += shade[k] * s.values[k];
    den += shade[k] * shade[k];
  }
  ReflectanceFit fit;
  fit.model = "lambert";
  fit.parameters = Eigen::VectorXd::Constant(1, den > 0 ? num / den : 0);
  for (auto& v : shade) v *= fit.parameters(0);
  score(s, shade, fit);
  return fit;
}

ReflectanceFit fit_bipolynomial_model(const ReflectanceSamples& s, int order) {
  const int terms = bipolynomial_term_count(order);
  require_samples(s, static_cast<std::size_t>(terms), bipolynomial_name(order));
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(terms, terms);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(terms), basis(terms);
  for (std::size_t k = 0; k < s.size(); ++k) {
    const Vec3 h = half_vector(s.lights[k]);
    bipolynomial_basis(order, s.normals[k].dot(h), s.lights[k].dot(h), basis.data());
    basis *= std::max(s.normals[k].dot(s.lights[k]), 0.0);
    gram.selfadjointView<Eigen::Lower>().rankUpdate(basis);
    rhs += s.values[k] * basis;
  }
  gram = gram.selfadjointView<Eigen::Lower>();
  gram.diagonal().array() += 1e-12 * std::max(gram.trace(), 1e-300);
  ReflectanceFit fit;
  fit.model = bipolynomial_name(order);
  fit.parameters = gram.ldlt().solve(rhs);
  std::vector<double> predicted(s.size());
  for (std::size_t k = 0; k < s.size(); ++k) {
    predicted[k] = evaluate_bipolynomial(order, fit.parameters, s.normals[k], s.lights[k]) *
                   std::max(s.normals[k].dot(s.lights[k]), 0.0);
  }
  score(s, predicted, fit);
  return fit;
}

double cook_torrance_lobe(const Vec3& n, const Vec3& l, const Vec3& v, double m, double f0) {
  const double nl = n.dot(l), nv = n.dot(v);
  if (nl <= 0 || nv <= 0) return 0;
  const Vec3 h = (l + v).normalized();
  const double nh = std::max(n.dot(h), 1e-6), vh = std::max(v.dot(h), 1e-6);
  const double nh2 = nh * nh;
  const double d = std::exp((nh2 - 1) / (nh2 * m * m)) / (kPi * m * m * nh2 * nh2);
  const double f = f0 + (1 - f0) * std::pow(1 - vh, 5);
  const double g = std::min({1.0, 2 * nh * nv / vh, 2 * nh * nl / vh});
  return kPi * d * f * g / (4 * nl * nv);
}

ReflectanceFit fit_cook_torrance(const ReflectanceSamples& s) {
  require_samples(s, 3, "cook-torrance");
  const Vec3 v = Vec3::UnitZ();
  ReflectanceFit best;
  best.model = "cook-torrance";
  double best_error = std::numeric_limits<double>::infinity();
  std::vector<double> shade(s.size()), lobe(s.size());
  for (std::size_t k = 0; k < s.size(); ++k) shade[k] = std::max(s.normals[k].dot(s.lights[k]), 0.0);
  for (const double f0 : {0.04, 0.2, 0.5, 0.9}) {
    for (int step = 0; step < 24; ++step) {
      const double m = 0.04 * std::pow(1.16, step);  // 0.04 .. ~1.2
      Eigen::Matrix2d gram = Eigen::Matrix2d::Zero();
      Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
      for (std::size_t k = 0; k < s.size(); ++k) {
        lobe[k] = cook_torrance_lobe(s.normals[k], s.lights[k], v, m, f0) * shade[k];
        const Eigen::Vector2d a(shade[k], lobe[k]);
        gram += a * a.transpose();
        rhs += s.values[k] * a;
      }
      Eigen::Vector2d x = gram.ldlt().solve(rhs);
      // kd, ks ≥ 0: fall back to the better one-term fit when the pair goes negative.
      if (!(x.allFinite()) || x(0) < 0 || x(1) < 0) {
        const Eigen::Vector2d only_kd(gram(0, 0) > 0 ? std::max(rhs(0) / gram(0, 0), 0.0) : 0, 0);
        const Eigen::Vector2d only_ks(0, gram(1, 1) > 0 ? std::max(rhs(1) / gram(1, 1), 0.0) : 0);
        auto err = [&](const Eigen::Vector2d& c) { return c.dot(gram * c) - 2 * c.dot(rhs); };
        x = err(only_kd) <= err(only_ks) ? only_kd : only_ks;
      }
      const double error = x.dot(gram * x) - 2 * x.dot(rhs);
      if (error < best_error) {
        best_error = error;
        best.parameters = Eigen::Vector4d(x(0), x(1), m, f0);
      }
    }
  }
  std::vector<double> predicted(s.size());
  for (std::size_t k = 0; k < s.size(); ++k) {
    predicted[k] = (best.parameters(0) + best.parameters(1) * cook_torrance_lobe(s.normals[k], s.lights[k], v,
                                                                                 best.parameters(2),
                                                                                 best.parameters(3))) *
                   shade[k];
  }
  score(s, predicted, best);
  return best;
}

}  // namespace lightstage
