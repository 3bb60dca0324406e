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

// The default candidates for λ: none, then roughly half-decades up to the prior alone.
const std::vector<double> kDefaultLambdas = {0, 1e-3, 3e-3, 0.01, 0.03, 0.1, 0.3, 1, 3, 10, 100, 1000};
// Keeps a system with undetermined terms solvable (λ = 0) without biasing it.
constexpr double kWhisperRidge = 1e-10;

// The model's terms: the bi-polynomial's, then the lobe's weight when lobe > 0.
struct Model {
  int order = 2;
  double lobe = 0;  // the lobe's width m; 0 = none
  int terms() const { return bipolynomial_term_count(order) + (lobe > 0 ? 1 : 0); }
};

// One pixel's observations in the model's terms: the rows a light in front
// of the normal gives, a_j = (n·l_j) (b(x_j, y_j), D(n·h_j)), and their values.
struct PixelRows {
  Eigen::MatrixXd design;  // rows × terms
  Eigen::VectorXd values;  // rows
  std::vector<int> image;  // the image of each row
  std::vector<std::uint8_t> lit;
  double lambert = 0;  // median of v / (n·l) over the lit rows; 0 when none
  int lit_rows = 0;
};

void pixel_rows(const PixelObservations& scratch, const Eigen::Vector3d& n, const Model& model,
                double threshold, PixelRows& out) {
  const int polynomial = bipolynomial_term_count(model.order);
  const Eigen::Index images = scratch.count();
  out.design.resize(images, model.terms());
  out.values.resize(images);
  out.image.clear();
  out.lit.clear();
  std::vector<double> ratios;
  Eigen::VectorXd basis(polynomial);
  Eigen::Index rows = 0;
  for (Eigen::Index j = 0; j < images; ++j) {
    if (!scratch.usable[static_cast<std::size_t>(j)]) continue;
    const Eigen::Vector3d l = scratch.lights.row(j).transpose();
    const double shade = n.dot(l);
    if (!(shade > 0)) continue;
    const Eigen::Vector3d h = (l + Eigen::Vector3d::UnitZ()).normalized();
    bipolynomial_basis(model.order, n.dot(h), l.dot(h), basis.data());
    out.design.row(rows).head(polynomial) = shade * basis.transpose();
    if (model.lobe > 0) out.design(rows, polynomial) = shade * specular_lobe(n.dot(h), model.lobe);
    out.values(rows) = scratch.values(j);
    out.image.push_back(static_cast<int>(j));
    const bool lit = scratch.values(j) > threshold;
    out.lit.push_back(lit ? 1 : 0);
    if (lit) ratios.push_back(scratch.values(j) / shade);
    ++rows;
  }
  out.design.conservativeResize(rows, model.terms());
  out.values.conservativeResize(rows);
  out.lit_rows = static_cast<int>(ratios.size());
  out.lambert = 0;
  if (!ratios.empty()) {
    const auto mid = ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2);
    std::nth_element(ratios.begin(), mid, ratios.end());
    out.lambert = *mid;
  }
}

bool held(const PixelRows& rows, Eigen::Index r, int folds, int fold) {
  return rows.image[static_cast<std::size_t>(r)] % folds == fold;
}

// Normal equations of the lit rows: G = Σ a aᵀ, b = Σ a v.
void lit_normal_equations(const PixelRows& rows, Eigen::MatrixXd& gram, Eigen::VectorXd& rhs) {
  const Eigen::Index terms = rows.design.cols();
  gram.setZero(terms, terms);
  rhs.setZero(terms);
  for (Eigen::Index r = 0; r < rows.design.rows(); ++r) {
    if (!rows.lit[static_cast<std::size_t>(r)]) continue;
    gram.noalias() += rows.design.row(r).transpose() * rows.design.row(r);
    rhs.noalias() += rows.design.row(r).transpose() * rows.values(r);
  }
}

// The same per cross-validation fold, in one pass: gram[f] / rhs[f] over
// every lit row but fold f's, gram[folds] / rhs[folds] over all of them.
struct FoldEquations {
  std::vector<Eigen::MatrixXd> gram;
  std::vector<Eigen::VectorXd> rhs;
};

void fold_equations(const PixelRows& rows, int folds, FoldEquations& out) {
  const Eigen::Index terms = rows.design.cols();
  const auto all = static_cast<std::size_t>(folds);
  out.gram.assign(all + 1, Eigen::MatrixXd::Zero(terms, terms));
  out.rhs.assign(all + 1, Eigen::VectorXd::Zero(terms));
  for (Eigen::Index r = 0; r < rows.design.rows(); ++r) {
    if (!rows.lit[static_cast<std::size_t>(r)]) continue;
    const auto f = static_cast<std::size_t>(rows.image[static_cast<std::size_t>(r)] % folds);
    out.gram[f].noalias() += rows.design.row(r).transpose() * rows.design.row(r);
    out.rhs[f].noalias() += rows.design.row(r).transpose() * rows.values(r);
  }
  for (std::size_t f = 0; f < all; ++f) {
    out.gram[all] += out.gram[f];
    out.rhs[all] += out.rhs[f];
  }
  for (std::size_t f = 0; f < all; ++f) {
    out.gram[f] = out.gram[all] - out.gram[f];
    out.rhs[f] = out.rhs[all] - out.rhs[f];
  }
}

// c = (G + ΛD)⁻¹ (b + ΛD s g), s the pixel's least-squares scale of g; Λ per term.
Eigen::VectorXd regularised_coefficients(const Eigen::MatrixXd& gram, const Eigen::VectorXd& rhs,
                                         const Eigen::VectorXd& g, const Eigen::VectorXd& penalty,
                                         double fallback_scale) {
  const double gg = g.dot(gram * g);
  const double scale = gg > 0 ? std::max(0.0, g.dot(rhs) / gg) : fallback_scale;
  Eigen::MatrixXd system = gram;
  system.diagonal() += penalty;
  system.diagonal().array() += kWhisperRidge * std::max(system.trace(), 1e-300);
  const Eigen::VectorXd c = system.ldlt().solve(rhs + penalty.cwiseProduct(scale * g));
  return c.allFinite() ? c : Eigen::VectorXd(scale * g);
}

Eigen::Vector3d normal_at(const cv::Mat& normals, const cv::Point& at) {
  const cv::Vec3f v = normals.at<cv::Vec3f>(at);
  return Eigen::Vector3d(v[0], v[1], v[2]).normalized();
}

// A solved pixel whose coefficients are refitted: a finite normal of about unit length.
bool refittable(const cv::Mat& normals, const cv::Mat& solved, const cv::Point& at) {
  const cv::Vec3f n = normals.at<cv::Vec3f>(at);
  return solved.at<std::uint8_t>(at) != 0 && std::isfinite(n[0] + n[1] + n[2]) && cv::norm(n) > 0.5;
}

void check_maps(const Observations& observations, const cv::Mat& normals, const cv::Mat& solved,
                const char* who) {
  check_observations(observations, who);
  if (normals.type() != CV_32FC3 || solved.type() != CV_8UC1 || normals.size() != observations.size ||
      solved.size() != observations.size)
    fail("{}: needs CV_32FC3 normals and a CV_8UC1 solved map of the observations' size {}x{}", who,
         observations.size.width, observations.size.height);
}

// The sample's rows, made once per model.
std::vector<PixelRows> sample_rows(const RelightingSample& sample, const Model& model,
                                   const RelightingFitOptions& options) {
  std::vector<PixelRows> rows(sample.size());
  parallel_chunks(sample.size(), options.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      pixel_rows(sample.pixel(i), sample.normal(i), model, options.shadow_threshold, rows[i]);
  });
  return rows;
}

// The object BRDF per fold (index folds: from every light): least squares of
// the lit rows outside the fold, values over the pixel's Lambertian albedo;
// and the weights D. Summed in sample order, so independent of threads.
struct ObjectBrdf {
  std::vector<Eigen::VectorXd> per_fold;  // folds + 1
  Eigen::VectorXd weights;
};

ObjectBrdf object_brdf(const std::vector<PixelRows>& sample, int terms, int folds) {
  std::vector<Eigen::MatrixXd> gram(static_cast<std::size_t>(folds + 1), Eigen::MatrixXd::Zero(terms, terms));
  std::vector<Eigen::VectorXd> rhs(static_cast<std::size_t>(folds + 1), Eigen::VectorXd::Zero(terms));
  ObjectBrdf out;
  out.weights = Eigen::VectorXd::Zero(terms);
  std::size_t counted = 0;
  FoldEquations equations;
  for (const PixelRows& rows : sample) {
    if (!(rows.lambert > 0)) continue;
    ++counted;
    fold_equations(rows, folds, equations);
    for (std::size_t slot = 0; slot < gram.size(); ++slot) {
      gram[slot] += equations.gram[slot];
      rhs[slot] += equations.rhs[slot] / rows.lambert;
    }
    out.weights += equations.gram.back().diagonal();
  }
  if (counted > 0) out.weights /= static_cast<double>(counted);
  for (std::size_t f = 0; f < gram.size(); ++f) {
    Eigen::MatrixXd system = gram[f];
    system.diagonal().array() += kWhisperRidge * std::max(system.trace(), 1e-300);
    Eigen::VectorXd solution = system.ldlt().solve(rhs[f]);
    if (!solution.allFinite()) {
      solution = Eigen::VectorXd::Zero(terms);
      solution(0) = 1;  // Lambertian
    }
    out.per_fold.push_back(solution);
  }
  return out;
}

// Cross-validated squared error of the relit held-out rows for each penalty
// vector, relative to the held-out energy (relative RMSE).
std::vector<double> cross_validate(const std::vector<PixelRows>& sample, const ObjectBrdf& object,
                                   const std::vector<Eigen::VectorXd>& penalties, int folds, int threads) {
  const auto count = static_cast<Eigen::Index>(penalties.size());
  Eigen::MatrixXd errors = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(sample.size()), count);
  Eigen::VectorXd energy = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(sample.size()));
  parallel_chunks(sample.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    FoldEquations equations;
    for (std::size_t i = begin; i < end; ++i) {
      const PixelRows& rows = sample[i];
      const auto at = static_cast<Eigen::Index>(i);
      fold_equations(rows, folds, equations);
      for (int f = 0; f < folds; ++f) {
        const auto slot = static_cast<std::size_t>(f);
        for (Eigen::Index c = 0; c < count; ++c) {
          const Eigen::VectorXd coefficients = regularised_coefficients(
              equations.gram[slot], equations.rhs[slot], object.per_fold[static_cast<std::size_t>(f)],
              penalties[static_cast<std::size_t>(c)], rows.lambert);
          for (Eigen::Index r = 0; r < rows.design.rows(); ++r) {
            if (!held(rows, r, folds, f)) continue;
            const double e = std::max(rows.design.row(r).dot(coefficients), 0.0) - rows.values(r);
            errors(at, c) += e * e;
          }
        }
      }
      for (Eigen::Index r = 0; r < rows.design.rows(); ++r) energy(at) += rows.values(r) * rows.values(r);
    }
  });
  const double reference = std::max(energy.sum(), std::numeric_limits<double>::min());
  std::vector<double> out;
  for (Eigen::Index c = 0; c < count; ++c) out.push_back(std::sqrt(errors.col(c).sum() / reference));
  return out;
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
  for (const double l : lobe_lambdas)
    if (!(std::isfinite(l) && l >= 0))
      fail("RelightingFitOptions.lobe_lambdas: must be finite and >= 0, got {}", l);
  for (const double m : lobe_widths)
    if (!(std::isfinite(m) && m > 0 && m <= kMaxLobeWidth))
      fail("RelightingFitOptions.lobe_widths: must be in (0, {}], got {}", kMaxLobeWidth, m);
  if (!(std::isfinite(min_lobe_gain) && min_lobe_gain >= 0))
    fail("RelightingFitOptions.min_lobe_gain: must be finite and >= 0, got {}", min_lobe_gain);
  if (folds < 2) fail("RelightingFitOptions.folds: must be at least 2, got {}", folds);
  if (sample_pixels < 1)
    fail("RelightingFitOptions.sample_pixels: must be at least 1, got {}", sample_pixels);
  if (threads < 0) fail("RelightingFitOptions.threads: must be 0 (automatic) or positive, got {}", threads);
}

nlohmann::json RelightingFit::to_json() const {
  nlohmann::json cv = nlohmann::json::array();
  for (const auto& [l, e] : validation) cv.push_back({{"lambda", l}, {"relative_rmse", e}});
  nlohmann::json lobes = nlohmann::json::array();
  for (const auto& [m, l, e] : lobe_validation)
    lobes.push_back({{"width", m}, {"lambda", l}, {"relative_rmse", e}});
  std::vector<double> g(object_brdf.data(), object_brdf.data() + object_brdf.size());
  return {{"observations", "every lit, unsaturated observation at the solved normal"},
          {"prior", "object BRDF times a per-pixel scale"},
          {"object_brdf", g},
          {"lambda", lambda},
          {"lambda_chosen_by", validation.empty() ? "fixed" : "cross-validation over the lights"},
          {"validation", cv},
          {"lobe_validation", lobes},
          {"lobe_lambda", lobe_lambda},
          {"pixels", pixels}};
}

std::size_t count_refittable_pixels(const cv::Mat& normals, const cv::Mat& solved) {
  if (normals.type() != CV_32FC3 || solved.type() != CV_8UC1 || normals.size() != solved.size())
    fail("count_refittable_pixels: needs CV_32FC3 normals and a CV_8UC1 solved map of their size");
  std::size_t count = 0;
  for (int y = 0; y < normals.rows; ++y)
    for (int x = 0; x < normals.cols; ++x) count += refittable(normals, solved, {x, y}) ? 1 : 0;
  return count;
}

RelightingSample::RelightingSample(std::size_t refittable_pixels, const RelightingFitOptions& options)
    : total_(refittable_pixels), limit_(static_cast<std::size_t>(options.sample_pixels)) {
  options.check();
}

void RelightingSample::add(const Observations& observations, const cv::Mat& normals, const cv::Mat& solved) {
  check_maps(observations, normals, solved, "RelightingSample");
  // Evenly spread: member i is refittable pixel floor(i · total / limit), every one when they are fewer.
  const auto member = [&](std::size_t i) { return total_ <= limit_ ? i : i * total_ / limit_; };
  for (std::size_t p = 0; p < observations.pixel_count(); ++p) {
    const cv::Point& at = observations.pixels[p];
    if (!refittable(normals, solved, at)) continue;
    if (seen_ >= total_) fail("RelightingSample: more refittable pixels than the {} it was made for", total_);
    if (normals_.size() < std::min(total_, limit_) && member(normals_.size()) == seen_) {
      pixels_.emplace_back();
      load_pixel(observations, p, true, pixels_.back());
      normals_.push_back(normal_at(normals, at));
    }
    ++seen_;
  }
}

RelightingFit fit_relighting_model(const RelightingSample& sample, const RelightingFitOptions& options) {
  options.check();
  if (sample.seen() != sample.total())
    fail("RelightingSample: {} of the {} refittable pixels it was made for were added", sample.seen(),
         sample.total());
  const int folds = options.folds;
  const int polynomial = bipolynomial_term_count(options.order);
  RelightingFit fit;
  fit.order = options.order;
  Model model{options.order, 0};
  std::vector<PixelRows> rows = sample_rows(sample, model, options);
  ObjectBrdf object = object_brdf(rows, model.terms(), folds);
  if (options.lambda) {
    fit.lambda = *options.lambda;
  } else {
    const std::vector<double>& candidates = options.lambdas.empty() ? kDefaultLambdas : options.lambdas;
    std::vector<Eigen::VectorXd> penalties;
    for (const double l : candidates) penalties.push_back(l * object.weights);
    const std::vector<double> errors = cross_validate(rows, object, penalties, folds, options.threads);
    std::size_t best = 0;
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      fit.validation.emplace_back(candidates[c], errors[c]);
      if (errors[c] < errors[best]) best = c;
    }
    fit.lambda = candidates[best];
    // One model's rows held at a time (they are most of the refit's memory).
    std::vector<PixelRows>().swap(rows);
    // The lobe: every width with every λ of its weight, at the polynomial's λ.
    double best_error = errors[best] * (1 - options.min_lobe_gain);
    if (options.specular_lobe) {
      for (const double m : options.lobe_widths) {
        const Model lobed{options.order, m};
        const std::vector<PixelRows> lobe_rows = sample_rows(sample, lobed, options);
        const ObjectBrdf lobe_object = object_brdf(lobe_rows, lobed.terms(), folds);
        std::vector<Eigen::VectorXd> lobe_penalties;
        for (const double l : options.lobe_lambdas) {
          Eigen::VectorXd p = fit.lambda * lobe_object.weights;
          p(polynomial) = l * lobe_object.weights(polynomial);
          lobe_penalties.push_back(p);
        }
        const std::vector<double> lobe_errors =
            cross_validate(lobe_rows, lobe_object, lobe_penalties, folds, options.threads);
        for (std::size_t c = 0; c < lobe_errors.size(); ++c) {
          fit.lobe_validation.push_back({m, options.lobe_lambdas[c], lobe_errors[c]});
          if (lobe_errors[c] < best_error) {
            best_error = lobe_errors[c];
            object = lobe_object;  // the chosen width's object BRDF, kept rather than refitted
            fit.lobe_width = m;
            fit.lobe_lambda = options.lobe_lambdas[c];
          }
        }
      }
    }
  }
  fit.object_brdf = object.per_fold[static_cast<std::size_t>(folds)];
  fit.penalty = fit.lambda * object.weights;
  if (fit.lobe_width > 0) fit.penalty(polynomial) = fit.lobe_lambda * object.weights(polynomial);
  return fit;
}

cv::Mat refit_coefficients(const Observations& observations, const cv::Mat& normals, const cv::Mat& solved,
                           RelightingFit& fit, const RelightingFitOptions& options, const cv::Mat& fallback) {
  check_maps(observations, normals, solved, "fit_relighting_brdf");
  const int polynomial = bipolynomial_term_count(fit.order);
  if (!fallback.empty() && (fallback.size() != observations.size || fallback.type() != CV_32FC(polynomial)))
    fail("fit_relighting_brdf: the fallback coefficients must be CV_32FC({}) of the observations' size",
         polynomial);
  std::vector<std::size_t> pixels;
  for (std::size_t p = 0; p < observations.pixel_count(); ++p)
    if (refittable(normals, solved, observations.pixels[p])) pixels.push_back(p);
  const Model model{fit.order, fit.lobe_width};
  const int terms = model.terms();
  cv::Mat coefficients(observations.size, CV_32FC(terms), cv::Scalar::all(0));
  std::vector<std::uint8_t> refitted(pixels.size(), 0);
  parallel_chunks(pixels.size(), options.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    PixelObservations scratch;
    PixelRows pixel;
    Eigen::MatrixXd gram;
    Eigen::VectorXd rhs;
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t p = pixels[i];
      const cv::Point& at = observations.pixels[p];
      load_pixel(observations, p, true, scratch);
      pixel_rows(scratch, normal_at(normals, at), model, options.shadow_threshold, pixel);
      auto* out = coefficients.ptr<float>(at.y) + static_cast<std::ptrdiff_t>(at.x) * terms;
      if (pixel.lit_rows == 0) {
        // Nothing lit in front of the normal: the fallback's polynomial, no lobe.
        if (!fallback.empty()) {
          const auto* given = fallback.ptr<float>(at.y) + static_cast<std::ptrdiff_t>(at.x) * polynomial;
          std::copy(given, given + polynomial, out);
        }
        continue;
      }
      refitted[i] = 1;
      lit_normal_equations(pixel, gram, rhs);
      const Eigen::VectorXd c =
          regularised_coefficients(gram, rhs, fit.object_brdf, fit.penalty, pixel.lambert);
      for (int t = 0; t < terms; ++t) out[t] = static_cast<float>(c(t));
    }
  });
  fit.pixels += static_cast<std::size_t>(std::count(refitted.begin(), refitted.end(), 1));
  return coefficients;
}

RelightingFit fit_relighting_brdf(const Observations& observations, const cv::Mat& normals,
                                  const cv::Mat& solved, const RelightingFitOptions& options,
                                  const cv::Mat& fallback) {
  options.check();
  check_maps(observations, normals, solved, "fit_relighting_brdf");
  RelightingSample sample(count_refittable_pixels(normals, solved), options);
  sample.add(observations, normals, solved);
  RelightingFit fit = fit_relighting_model(sample, options);
  fit.coefficients = refit_coefficients(observations, normals, solved, fit, options, fallback);
  return fit;
}

}  // namespace lightstage
