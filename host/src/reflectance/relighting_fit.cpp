#include "lightstage/host/reflectance/relighting_fit.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/reflectance/bipolynomial_model.hpp"
#include "lightstage/host/solvers/pixel_observations.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace lightstage {
namespace {

// The default candidates for λ: none, then half-decades up to the prior alone.
const std::vector<double> kDefaultLambdas = {0, 1e-3, 3e-3, 0.01, 0.03, 0.1, 0.3, 1, 3, 10, 100, 1000};
// Keeps a system with undetermined terms solvable (λ = 0) without biasing it.
constexpr double kWhisperRidge = 1e-10;
// Pixels the object BRDF is fitted on at most (evenly spread).
constexpr std::size_t kObjectBrdfPixels = 20000;

// One pixel's observations in the relighting model's terms: the rows a light
// in front of the normal gives, a_j = (n·l_j) b(x_j, y_j), and their values.
struct PixelRows {
  Eigen::MatrixXd design;  // rows × terms
  Eigen::VectorXd values;  // rows
  std::vector<int> image;  // the image of each row
  std::vector<std::uint8_t> lit;
  double lambert = 0;  // median of v / (n·l) over the lit rows; 0 when none
  int lit_rows = 0;
};

void pixel_rows(const Observations& observations, std::size_t p, const Eigen::Vector3d& n, int order,
                double threshold, PixelObservations& scratch, PixelRows& out) {
  load_pixel(observations, p, true, scratch);
  const int terms = bipolynomial_term_count(order);
  const Eigen::Index images = scratch.count();
  out.design.resize(images, terms);
  out.values.resize(images);
  out.image.clear();
  out.lit.clear();
  std::vector<double> ratios;
  Eigen::VectorXd basis(terms);
  Eigen::Index rows = 0;
  for (Eigen::Index j = 0; j < images; ++j) {
    if (!scratch.usable[static_cast<std::size_t>(j)]) continue;
    const Eigen::Vector3d l = scratch.lights.row(j).transpose();
    const double shade = n.dot(l);
    if (!(shade > 0)) continue;
    const Eigen::Vector3d h = (l + Eigen::Vector3d::UnitZ()).normalized();
    bipolynomial_basis(order, n.dot(h), l.dot(h), basis.data());
    out.design.row(rows) = shade * basis.transpose();
    out.values(rows) = scratch.values(j);
    out.image.push_back(static_cast<int>(j));
    const bool lit = scratch.values(j) > threshold;
    out.lit.push_back(lit ? 1 : 0);
    if (lit) ratios.push_back(scratch.values(j) / shade);
    ++rows;
  }
  out.design.conservativeResize(rows, terms);
  out.values.conservativeResize(rows);
  out.lit_rows = static_cast<int>(ratios.size());
  out.lambert = 0;
  if (!ratios.empty()) {
    const auto mid = ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2);
    std::nth_element(ratios.begin(), mid, ratios.end());
    out.lambert = *mid;
  }
}

// Normal equations of the lit rows whose image is not in `held_fold`
// (-1 = none held): G = Σ a aᵀ, b = Σ a v.
void lit_normal_equations(const PixelRows& rows, int folds, int held_fold, Eigen::MatrixXd& gram,
                          Eigen::VectorXd& rhs) {
  const Eigen::Index terms = rows.design.cols();
  gram.setZero(terms, terms);
  rhs.setZero(terms);
  for (Eigen::Index r = 0; r < rows.design.rows(); ++r) {
    const auto u = static_cast<std::size_t>(r);
    if (!rows.lit[u] || (held_fold >= 0 && rows.image[u] % folds == held_fold)) continue;
    gram.noalias() += rows.design.row(r).transpose() * rows.design.row(r);
    rhs.noalias() += rows.design.row(r).transpose() * rows.values(r);
  }
}

// c = (G + λD)⁻¹ (b + λ D s g), s the pixel's least-squares scale of g.
Eigen::VectorXd regularised_coefficients(const Eigen::MatrixXd& gram, const Eigen::VectorXd& rhs,
                                         const Eigen::VectorXd& g, const Eigen::VectorXd& weights,
                                         double lambda, double fallback_scale) {
  const double gg = g.dot(gram * g);
  const double scale = gg > 0 ? std::max(0.0, g.dot(rhs) / gg) : fallback_scale;
  Eigen::MatrixXd system = gram;
  system.diagonal() += lambda * weights;
  system.diagonal().array() += kWhisperRidge * std::max(system.trace(), 1e-300);
  const Eigen::VectorXd c = system.ldlt().solve(rhs + lambda * weights.cwiseProduct(scale * g));
  return c.allFinite() ? c : Eigen::VectorXd(scale * g);
}

// Evenly spread pixel indices, at most `limit` of the solved ones.
std::vector<std::size_t> sample_pixels(const std::vector<std::size_t>& solved, std::size_t limit) {
  if (solved.size() <= limit) return solved;
  std::vector<std::size_t> out;
  out.reserve(limit);
  for (std::size_t i = 0; i < limit; ++i) out.push_back(solved[i * solved.size() / limit]);
  return out;
}

Eigen::Vector3d normal_at(const cv::Mat& normals, const cv::Point& at) {
  const cv::Vec3f v = normals.at<cv::Vec3f>(at);
  return Eigen::Vector3d(v[0], v[1], v[2]).normalized();
}

// Per fold (and, at index folds, for all lights): the object BRDF normal
// equations of the lit rows outside the fold, values divided by the pixel's
// Lambertian albedo; plus the weights D.
struct ObjectSystems {
  std::vector<Eigen::MatrixXd> gram;
  std::vector<Eigen::VectorXd> rhs;
  Eigen::VectorXd weights;
};

ObjectSystems object_systems(const Observations& observations, const cv::Mat& normals,
                             const std::vector<std::size_t>& pixels, const RelightingFitOptions& options) {
  const int terms = bipolynomial_term_count(options.order);
  const int folds = options.folds;
  struct Partial {
    std::vector<Eigen::MatrixXd> gram;
    std::vector<Eigen::VectorXd> rhs;
    Eigen::VectorXd weights;
    std::size_t pixels = 0;
  };
  std::vector<Partial> partial(static_cast<std::size_t>(resolve_threads(options.threads)));
  parallel_chunks(pixels.size(), options.threads, [&](std::size_t chunk, std::size_t begin, std::size_t end) {
    Partial& mine = partial[chunk];
    mine.gram.assign(static_cast<std::size_t>(folds + 1), Eigen::MatrixXd::Zero(terms, terms));
    mine.rhs.assign(static_cast<std::size_t>(folds + 1), Eigen::VectorXd::Zero(terms));
    mine.weights = Eigen::VectorXd::Zero(terms);
    PixelObservations scratch;
    PixelRows rows;
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t p = pixels[i];
      pixel_rows(observations, p, normal_at(normals, observations.pixels[p]), options.order,
                 options.shadow_threshold, scratch, rows);
      if (!(rows.lambert > 0)) continue;
      ++mine.pixels;
      for (Eigen::Index r = 0; r < rows.design.rows(); ++r) {
        const auto u = static_cast<std::size_t>(r);
        if (!rows.lit[u]) continue;
        const Eigen::VectorXd a = rows.design.row(r).transpose();
        mine.weights += a.cwiseAbs2();
        const Eigen::MatrixXd outer = a * a.transpose();
        const Eigen::VectorXd target = a * (rows.values(r) / rows.lambert);
        for (int f = 0; f <= folds; ++f) {
          if (f < folds && rows.image[u] % folds == f) continue;
          mine.gram[static_cast<std::size_t>(f)] += outer;
          mine.rhs[static_cast<std::size_t>(f)] += target;
        }
      }
    }
  });
  ObjectSystems out;
  out.gram.assign(static_cast<std::size_t>(folds + 1), Eigen::MatrixXd::Zero(terms, terms));
  out.rhs.assign(static_cast<std::size_t>(folds + 1), Eigen::VectorXd::Zero(terms));
  out.weights = Eigen::VectorXd::Zero(terms);
  std::size_t counted = 0;
  for (const Partial& mine : partial) {
    if (mine.gram.empty()) continue;
    for (std::size_t f = 0; f < out.gram.size(); ++f) {
      out.gram[f] += mine.gram[f];
      out.rhs[f] += mine.rhs[f];
    }
    out.weights += mine.weights;
    counted += mine.pixels;
  }
  if (counted > 0) out.weights /= static_cast<double>(counted);
  return out;
}

Eigen::VectorXd solve_object_brdf(const Eigen::MatrixXd& gram, const Eigen::VectorXd& rhs) {
  Eigen::MatrixXd system = gram;
  system.diagonal().array() += kWhisperRidge * std::max(system.trace(), 1e-300);
  const Eigen::VectorXd g = system.ldlt().solve(rhs);
  if (g.allFinite()) return g;
  Eigen::VectorXd lambertian = Eigen::VectorXd::Zero(rhs.size());
  lambertian(0) = 1;
  return lambertian;
}

}  // namespace

void RelightingFitOptions::check() const {
  bipolynomial_term_count(order);  // names the order when it is out of range
  if (!(std::isfinite(shadow_threshold) && shadow_threshold >= 0))
    fail("RelightingFitOptions.shadow_threshold: must be finite and >= 0, got {}", shadow_threshold);
  if (lambda && !(std::isfinite(*lambda) && *lambda >= 0))
    fail("RelightingFitOptions.lambda: must be finite and >= 0, got {}", *lambda);
  for (const double l : lambdas)
    if (!(std::isfinite(l) && l >= 0))
      fail("RelightingFitOptions.lambdas: must be finite and >= 0, got {}", l);
  if (folds < 2) fail("RelightingFitOptions.folds: must be at least 2, got {}", folds);
  if (sample_pixels < 1)
    fail("RelightingFitOptions.sample_pixels: must be at least 1, got {}", sample_pixels);
  if (threads < 0) fail("RelightingFitOptions.threads: must be 0 (automatic) or positive, got {}", threads);
}

nlohmann::json RelightingFit::to_json() const {
  nlohmann::json cv = nlohmann::json::array();
  for (const auto& [l, e] : validation) cv.push_back({{"lambda", l}, {"relative_rmse", e}});
  std::vector<double> g(object_brdf.data(), object_brdf.data() + object_brdf.size());
  return {{"observations", "every lit, unsaturated observation at the solved normal"},
          {"prior", "object BRDF times a per-pixel scale"},
          {"object_brdf", g},
          {"lambda", lambda},
          {"lambda_chosen_by", validation.empty() ? "fixed" : "cross-validation over the lights"},
          {"validation", cv},
          {"pixels", pixels}};
}

RelightingFit fit_relighting_brdf(const Observations& observations, const cv::Mat& normals,
                                  const cv::Mat& solved, const RelightingFitOptions& options) {
  options.check();
  check_observations(observations, "fit_relighting_brdf");
  if (normals.type() != CV_32FC3 || solved.type() != CV_8UC1 || normals.size() != observations.size ||
      solved.size() != observations.size)
    fail(
        "fit_relighting_brdf: needs CV_32FC3 normals and a CV_8UC1 solved map of the observations' size "
        "{}x{}",
        observations.size.width, observations.size.height);
  const int terms = bipolynomial_term_count(options.order);
  const int folds = options.folds;

  std::vector<std::size_t> solved_pixels;
  for (std::size_t p = 0; p < observations.pixel_count(); ++p) {
    const cv::Point& at = observations.pixels[p];
    const cv::Vec3f n = normals.at<cv::Vec3f>(at);
    if (solved.at<std::uint8_t>(at) != 0 && std::isfinite(n[0] + n[1] + n[2]) && cv::norm(n) > 0.5)
      solved_pixels.push_back(p);
  }
  RelightingFit fit;
  fit.coefficients = cv::Mat(observations.size, CV_32FC(terms), cv::Scalar::all(0));
  fit.pixels = solved_pixels.size();
  const ObjectSystems systems =
      object_systems(observations, normals, sample_pixels(solved_pixels, kObjectBrdfPixels), options);
  fit.object_brdf = solve_object_brdf(systems.gram[static_cast<std::size_t>(folds)],
                                      systems.rhs[static_cast<std::size_t>(folds)]);
  const Eigen::VectorXd& weights = systems.weights;

  if (options.lambda) {
    fit.lambda = *options.lambda;
  } else {
    // Cross-validation: per sampled pixel and candidate, the squared error of
    // the relit held-out values; summed in pixel order (thread-independent).
    const std::vector<double>& candidates = options.lambdas.empty() ? kDefaultLambdas : options.lambdas;
    const std::vector<std::size_t> sample =
        sample_pixels(solved_pixels, static_cast<std::size_t>(options.sample_pixels));
    std::vector<Eigen::VectorXd> object_brdf(static_cast<std::size_t>(folds));
    for (int f = 0; f < folds; ++f)
      object_brdf[static_cast<std::size_t>(f)] = solve_object_brdf(systems.gram[static_cast<std::size_t>(f)],
                                                                   systems.rhs[static_cast<std::size_t>(f)]);
    const auto count = static_cast<Eigen::Index>(candidates.size());
    Eigen::MatrixXd errors = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(sample.size()), count);
    Eigen::VectorXd energy = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(sample.size()));
    parallel_chunks(sample.size(), options.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
      PixelObservations scratch;
      PixelRows rows;
      Eigen::MatrixXd gram;
      Eigen::VectorXd rhs;
      for (std::size_t i = begin; i < end; ++i) {
        const std::size_t p = sample[i];
        pixel_rows(observations, p, normal_at(normals, observations.pixels[p]), options.order,
                   options.shadow_threshold, scratch, rows);
        const auto row = static_cast<Eigen::Index>(i);
        for (int f = 0; f < folds; ++f) {
          lit_normal_equations(rows, folds, f, gram, rhs);
          const Eigen::VectorXd& g = object_brdf[static_cast<std::size_t>(f)];
          for (Eigen::Index c = 0; c < count; ++c) {
            const Eigen::VectorXd coefficients = regularised_coefficients(
                gram, rhs, g, weights, candidates[static_cast<std::size_t>(c)], rows.lambert);
            for (Eigen::Index r = 0; r < rows.design.rows(); ++r) {
              if (rows.image[static_cast<std::size_t>(r)] % folds != f) continue;
              const double relit = std::max(rows.design.row(r).dot(coefficients), 0.0);
              const double e = relit - rows.values(r);
              errors(row, c) += e * e;
            }
          }
          for (Eigen::Index r = 0; r < rows.design.rows(); ++r)
            if (rows.image[static_cast<std::size_t>(r)] % folds == f)
              energy(row) += rows.values(r) * rows.values(r);
        }
      }
    });
    const Eigen::RowVectorXd total = errors.colwise().sum();
    const double reference = std::max(energy.sum(), std::numeric_limits<double>::min());
    Eigen::Index best = 0;
    for (Eigen::Index c = 0; c < count; ++c) {
      fit.validation.emplace_back(candidates[static_cast<std::size_t>(c)], std::sqrt(total(c) / reference));
      if (total(c) < total(best)) best = c;
    }
    fit.lambda = candidates[static_cast<std::size_t>(best)];
  }

  parallel_chunks(
      solved_pixels.size(), options.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
        PixelObservations scratch;
        PixelRows rows;
        Eigen::MatrixXd gram;
        Eigen::VectorXd rhs;
        for (std::size_t i = begin; i < end; ++i) {
          const std::size_t p = solved_pixels[i];
          const cv::Point& at = observations.pixels[p];
          pixel_rows(observations, p, normal_at(normals, at), options.order, options.shadow_threshold,
                     scratch, rows);
          if (rows.lit_rows == 0) continue;
          lit_normal_equations(rows, folds, -1, gram, rhs);
          const Eigen::VectorXd c =
              regularised_coefficients(gram, rhs, fit.object_brdf, weights, fit.lambda, rows.lambert);
          auto* out = fit.coefficients.ptr<float>(at.y) + static_cast<std::ptrdiff_t>(at.x) * terms;
          for (int t = 0; t < terms; ++t) out[t] = static_cast<float>(c(t));
        }
      });
  return fit;
}

}  // namespace lightstage
