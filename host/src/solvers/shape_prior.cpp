#include "lightstage/host/solvers/shape_prior.hpp"

#include "lightstage/common/error.hpp"
#include "solvers/nelder_mead.hpp"

#include <fmt/format.h>
#include <Eigen/Dense>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

namespace lightstage {
namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// G: Gaussian smoothing of per-pixel rows over the image, as a normalised
// convolution restricted to `weight` (so the mask's edge does not pull values
// toward zero). Rows whose smoothed weight is tiny come back as zero.
RowMatrix smooth_rows(const RowMatrix& values, const std::vector<cv::Point>& pixels,
                      const std::vector<double>& weight, cv::Size size, double sigma) {
  if (sigma <= 0) {
    RowMatrix out = values;
    for (Eigen::Index i = 0; i < out.rows(); ++i)
      if (weight[static_cast<std::size_t>(i)] <= 0) out.row(i).setZero();
    return out;
  }
  const int ksize = 2 * static_cast<int>(std::ceil(3 * sigma)) + 1;
  cv::Mat w = cv::Mat::zeros(size, CV_64FC1);
  for (std::size_t i = 0; i < pixels.size(); ++i) w.at<double>(pixels[i]) = weight[i];
  cv::Mat w_smooth;
  cv::GaussianBlur(w, w_smooth, cv::Size(ksize, ksize), sigma, sigma, cv::BORDER_CONSTANT);
  RowMatrix out(values.rows(), values.cols());
  cv::Mat channel(size, CV_64FC1), smoothed;
  for (Eigen::Index k = 0; k < values.cols(); ++k) {
    channel.setTo(0);
    for (std::size_t i = 0; i < pixels.size(); ++i)
      channel.at<double>(pixels[i]) = weight[i] * values(static_cast<Eigen::Index>(i), k);
    cv::GaussianBlur(channel, smoothed, cv::Size(ksize, ksize), sigma, sigma, cv::BORDER_CONSTANT);
    for (std::size_t i = 0; i < pixels.size(); ++i) {
      const double ws = w_smooth.at<double>(pixels[i]);
      out(static_cast<Eigen::Index>(i), k) = ws > 1e-3 ? smoothed.at<double>(pixels[i]) / ws : 0.0;
    }
  }
  return out;
}

// Real spherical-harmonic polynomials of order 2 (k = 9) or 3 (k = 16) of a
// unit normal, unnormalised: the shading model's matrix absorbs the constants.
Eigen::RowVectorXd sh_basis(const Eigen::Vector3d& n, int k) {
  const double x = n.x(), y = n.y(), z = n.z();
  Eigen::RowVectorXd b(k);
  b.head<9>() << 1, x, y, z, x * y, x * z, y * z, x * x - y * y, 3 * z * z - 1;
  if (k == 16)
    b.tail<7>() << y * (3 * x * x - y * y), x * y * z, y * (5 * z * z - 1), z * (5 * z * z - 3),
        x * (5 * z * z - 1), z * (x * x - y * y), x * (x * x - 3 * y * y);
  return b;
}

// The photometric arbiter between the fit's and the prior's normal of each
// pixel. Shading model S̃ ≈ ρ Y(n) B (Y: sh_basis, ρ = |S̃ A|, B k×k). A
// normal's cost is the pixel's residual in image space within the rank-k
// subspace, min over ρ ≥ 0 of ‖(S̃ᵢ − ρ Y(n) B) Σ^½‖².
class ShadingModel {
 public:
  // B by least squares over the rows whose `normals` row is nonzero.
  ShadingModel(const RowMatrix& S, const RowMatrix& normals, const Eigen::VectorXd& rho,
               const Eigen::VectorXd& sigma)
      : S_(S), w_(sigma.cwiseSqrt().transpose()) {
    const Eigen::Index k = S.cols();
    Eigen::MatrixXd model(S.rows(), k), target(S.rows(), k);
    Eigen::Index rows = 0;
    for (Eigen::Index i = 0; i < S.rows(); ++i) {
      if (normals.row(i).isZero() || !(rho[i] > 0)) continue;
      model.row(rows) = rho[i] * sh_basis(normals.row(i).transpose(), static_cast<int>(k));
      target.row(rows++) = S.row(i);
    }
    fitted_ = rows >= k;
    if (fitted_) B_ = model.topRows(rows).colPivHouseholderQr().solve(target.topRows(rows));
  }

  // Fewer rows than k leave B undetermined: such a model judges nothing.
  bool fitted() const { return fitted_; }

  double cost(Eigen::Index i, const Eigen::Vector3d& n) const {
    const Eigen::RowVectorXd observed = S_.row(i).cwiseProduct(w_);
    const Eigen::RowVectorXd predicted = (sh_basis(n, static_cast<int>(S_.cols())) * B_).cwiseProduct(w_);
    const double t = observed.dot(predicted), len2 = predicted.squaredNorm();
    return observed.squaredNorm() - (t > 0 && len2 > 0 ? t * t / len2 : 0.0);
  }

 private:
  const RowMatrix& S_;
  Eigen::RowVectorXd w_;
  Eigen::MatrixXd B_;
  bool fitted_ = false;
};

struct PhotometricCosts {
  std::vector<double> fit, prior;  // per row; prior < 0 where the pixel has no prior
  bool model_from_prior = false;   // which normals the shading model was fitted to
};

// Two shading models, one fitted to the fit's normals and one to the prior's;
// the one whose own normals explain the images better (lower total cost over
// the pixels that have both) judges every pixel, so that the arbiter neither
// favours the fit it is to judge nor trusts a prior that explains nothing.
PhotometricCosts photometric_costs(const RowMatrix& S, const Eigen::MatrixXd& A, const RowMatrix& N,
                                   const Eigen::VectorXd& sigma) {
  const Eigen::Index p = S.rows();
  const RowMatrix SA = S * A;
  const Eigen::VectorXd rho = SA.rowwise().norm();
  RowMatrix F = RowMatrix::Zero(p, 3);
  for (Eigen::Index i = 0; i < p; ++i)
    if (rho[i] > 0 && std::isfinite(rho[i])) F.row(i) = SA.row(i) / rho[i];
  const ShadingModel from_fit(S, F, rho, sigma), from_prior(S, N, rho, sigma);
  double total_fit = 0, total_prior = 0;
  for (Eigen::Index i = 0; i < p; ++i) {
    if (F.row(i).isZero() || N.row(i).isZero() || !from_fit.fitted() || !from_prior.fitted()) continue;
    total_fit += from_fit.cost(i, F.row(i).transpose());
    total_prior += from_prior.cost(i, N.row(i).transpose());
  }
  PhotometricCosts out{std::vector<double>(static_cast<std::size_t>(p), 0.0),
                       std::vector<double>(static_cast<std::size_t>(p), -1.0),
                       from_prior.fitted() && (!from_fit.fitted() || total_prior <= total_fit)};
  const ShadingModel& judge = out.model_from_prior ? from_prior : from_fit;
  if (!judge.fitted()) return out;  // no judge: nothing is kept
  for (Eigen::Index i = 0; i < p; ++i) {
    const auto u = static_cast<std::size_t>(i);
    if (!F.row(i).isZero()) out.fit[u] = judge.cost(i, F.row(i).transpose());
    if (!N.row(i).isZero()) out.prior[u] = judge.cost(i, N.row(i).transpose());
  }
  return out;
}

double median(std::vector<double> values) {
  if (values.empty()) return 0;
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace

void ShapePriorOptions::check() const {
  if (sh_dimension != 9 && sh_dimension != 16)
    fail("shape-prior: sh dimension (--sh) must be 9 or 16, got {}", sh_dimension);
  if (!(smoothing_sigma >= 0) || smoothing_sigma > 100)
    fail("shape-prior: smoothing sigma must be in [0, 100] pixels, got {}", smoothing_sigma);
  if (max_evaluations < 0) fail("shape-prior: max_evaluations must not be negative, got {}", max_evaluations);
  if (refine_pixels < 100) fail("shape-prior: refine_pixels must be at least 100, got {}", refine_pixels);
  if (!(min_prior_fraction >= 0 && min_prior_fraction <= 1))
    fail("shape-prior: min_prior_fraction must be in [0, 1], got {}", min_prior_fraction);
  if (!(keep_prior_margin >= 0 && keep_prior_margin <= 10))
    fail("shape-prior: keep-prior margin (--keep-prior-margin) must be in [0, 10], got {}",
         keep_prior_margin);
}

nlohmann::json ShapePriorOptions::to_json() const {
  return {{"sh_dimension", sh_dimension},
          {"smoothing_sigma", smoothing_sigma},
          {"refine", refine},
          {"max_evaluations", max_evaluations},
          {"refine_pixels", refine_pixels},
          {"min_prior_fraction", min_prior_fraction},
          {"keep_prior", keep_prior},
          {"keep_prior_margin", keep_prior_margin}};
}

SolveResult solve_shape_prior(const Observations& obs, const cv::Mat& prior_normals,
                              const cv::Mat& prior_valid, const ShapePriorOptions& options) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  const int k = options.sh_dimension;
  const Eigen::Index p = static_cast<Eigen::Index>(obs.pixel_count());
  const Eigen::Index q = obs.intensities.cols();
  if (q < k) fail("shape-prior: needs at least k = {} images, the stack has {}", k, q);
  if (p < k) fail("shape-prior: needs at least k = {} pixels in the mask, got {}", k, p);
  if (prior_normals.type() != CV_32FC3 || prior_normals.size() != obs.size)
    fail("shape-prior: the prior normals must be CV_32FC3 of the images' size {}x{}", obs.size.width,
         obs.size.height);
  if (!prior_valid.empty() && (prior_valid.type() != CV_8UC1 || prior_valid.size() != obs.size))
    fail("shape-prior: the prior's validity mask must be CV_8UC1 of the images' size");

  // 1. Rank-k factorisation through the small q×q Gram matrix: I = U Σ Vᵀ,
  //    S̃ = U_k Σ_k^½ = I V_k Σ_k^-½.
  const RowMatrix I = obs.intensities.cast<double>();
  const Eigen::MatrixXd gram = I.transpose() * I;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram);
  Eigen::MatrixXd vk(q, k);
  Eigen::VectorXd sigma(k);
  for (int j = 0; j < k; ++j) {
    const Eigen::Index src = q - 1 - j;  // eigenvalues ascend
    vk.col(j) = eig.eigenvectors().col(src);
    sigma[j] = std::sqrt(std::max(eig.eigenvalues()[src], 0.0));
  }
  if (!(sigma[k - 1] > 1e-12 * sigma[0]))
    fail("shape-prior: the images span fewer than k = {} dimensions (is the lighting varying?)", k);
  const RowMatrix S = I * vk * sigma.cwiseSqrt().cwiseInverse().asDiagonal();

  // The prior on the observation rows.
  RowMatrix N(p, 3);
  std::vector<double> prior_weight(static_cast<std::size_t>(p), 0.0), all(static_cast<std::size_t>(p), 1.0);
  Eigen::Index with_prior = 0;
  for (Eigen::Index i = 0; i < p; ++i) {
    const cv::Point px = obs.pixels[static_cast<std::size_t>(i)];
    const cv::Vec3f n = prior_normals.at<cv::Vec3f>(px);
    const Eigen::Vector3d v(n[0], n[1], n[2]);
    const bool ok =
        (prior_valid.empty() || prior_valid.at<std::uint8_t>(px)) && v.allFinite() && v.norm() > 0.5;
    N.row(i) = ok ? Eigen::RowVector3d(v.normalized().transpose()) : Eigen::RowVector3d::Zero();
    if (ok) {
      prior_weight[static_cast<std::size_t>(i)] = 1.0;
      ++with_prior;
    }
  }
  if (with_prior < k || static_cast<double>(with_prior) < options.min_prior_fraction * static_cast<double>(p))
    fail("shape-prior: only {} of the mask's {} pixels have a prior normal (need {:.0f}%)", with_prior, p,
         100 * options.min_prior_fraction);

  // 2. Eq. 4.6 on smoothed data, over pixels with a prior.
  const RowMatrix GS = smooth_rows(S, obs.pixels, all, obs.size, options.smoothing_sigma);
  RowMatrix GN = smooth_rows(N, obs.pixels, prior_weight, obs.size, options.smoothing_sigma);
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < p; ++i) {
    const double len = GN.row(i).norm();
    if (prior_weight[static_cast<std::size_t>(i)] > 0 && len > 0.3) {
      GN.row(i) /= len;
      rows.push_back(i);
    }
  }
  if (static_cast<Eigen::Index>(rows.size()) < k)
    fail("shape-prior: too few pixels with a usable smoothed prior");
  Eigen::MatrixXd X(static_cast<Eigen::Index>(rows.size()), k), Y(static_cast<Eigen::Index>(rows.size()), 3);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    X.row(static_cast<Eigen::Index>(r)) = GS.row(rows[r]);
    Y.row(static_cast<Eigen::Index>(r)) = GN.row(rows[r]);
  }
  const Eigen::MatrixXd A0 = X.colPivHouseholderQr().solve(Y);

  // 3. Eq. 4.7 by Nelder–Mead on an even subsample of the same rows.
  const std::size_t stride =
      std::max<std::size_t>(1, rows.size() / static_cast<std::size_t>(options.refine_pixels));
  std::vector<Eigen::Index> sample;
  for (std::size_t r = 0; r < rows.size(); r += stride) sample.push_back(static_cast<Eigen::Index>(r));
  Eigen::MatrixXd Xs(static_cast<Eigen::Index>(sample.size()), k),
      Ys(static_cast<Eigen::Index>(sample.size()), 3);
  for (std::size_t r = 0; r < sample.size(); ++r) {
    Xs.row(static_cast<Eigen::Index>(r)) = X.row(sample[r]);
    Ys.row(static_cast<Eigen::Index>(r)) = Y.row(sample[r]);
  }
  auto cost = [&](const Eigen::MatrixXd& A) {
    const Eigen::MatrixXd M = Xs * A;
    double sum = 0;
    for (Eigen::Index i = 0; i < M.rows(); ++i) {
      const double len = M.row(i).norm();
      sum += len > 0 ? (M.row(i) / len - Ys.row(i)).squaredNorm() : 4.0;
    }
    return sum / static_cast<double>(M.rows());
  };
  const double initial_cost = cost(A0);
  Eigen::MatrixXd A = A0;
  double final_cost = initial_cost;
  int evaluations = 0;
  if (options.refine && options.max_evaluations > 0) {
    // Column-major parameter vector; steps scaled per column of A.
    Eigen::VectorXd x0 = Eigen::Map<const Eigen::VectorXd>(A0.data(), A0.size());
    Eigen::VectorXd step(x0.size());
    for (int c = 0; c < 3; ++c) {
      const double scale = std::max(A0.col(c).cwiseAbs().maxCoeff(), 1e-12);
      for (int r = 0; r < k; ++r) step[c * k + r] = 0.1 * scale;
    }
    // Progress in batches of evaluations; the rest is reported when the search stops early.
    constexpr std::size_t kReportEvery = 64;
    std::size_t unreported = 0, reported = 0;
    const auto nm = solvers::nelder_mead(
        [&](const Eigen::VectorXd& x) {
          if (options.progress && ++unreported == kReportEvery) {
            options.progress(unreported);
            reported += unreported;
            unreported = 0;
          }
          return cost(Eigen::Map<const Eigen::MatrixXd>(x.data(), k, 3));
        },
        x0, step, options.max_evaluations);
    evaluations = nm.evaluations;
    const auto budget = static_cast<std::size_t>(options.max_evaluations);
    if (options.progress && reported < budget) options.progress(budget - reported);
    if (nm.value < initial_cost) {
      A = Eigen::Map<const Eigen::MatrixXd>(nm.x.data(), k, 3);
      final_cost = nm.value;
    }
  }

  // Step 5 (the header), decided before the output: the pixels whose prior
  // normal the fit does not beat photometrically by more than the margin.
  std::vector<bool> keep(static_cast<std::size_t>(p), false);
  std::size_t kept = 0;
  double margin = 0;
  bool model_from_prior = false;
  if (options.keep_prior) {
    const PhotometricCosts costs = photometric_costs(S, A, N, sigma);
    model_from_prior = costs.model_from_prior;
    margin = options.keep_prior_margin * median(costs.fit);
    for (std::size_t i = 0; i < keep.size(); ++i)
      if (costs.prior[i] >= 0 && costs.prior[i] <= costs.fit[i] + margin) {
        keep[i] = true;
        ++kept;
      }
  }

  // 4. N* = O(S̃ A*), or the prior's normal where step 5 keeps it; the rank-k
  //    reconstruction error as the residual.
  const Eigen::MatrixXd lighting =
      sigma.cwiseSqrt().asDiagonal() * vk.transpose();  // k × q: I ≈ S̃ · lighting
  SolveResult result;
  result.normals = cv::Mat::zeros(obs.size, CV_32FC3);
  result.albedo = cv::Mat::zeros(obs.size, CV_32FC1);
  result.residual = cv::Mat::zeros(obs.size, CV_32FC1);
  result.solved = cv::Mat::zeros(obs.size, CV_8UC1);
  std::size_t solved = 0, degenerate = 0;
  for (Eigen::Index i = 0; i < p; ++i) {
    const Eigen::RowVector3d m = S.row(i) * A;
    const double len = m.norm();
    const cv::Point px = obs.pixels[static_cast<std::size_t>(i)];
    if (!(len > 0) || !std::isfinite(len)) {
      ++degenerate;
      continue;
    }
    const Eigen::RowVector3d n = keep[static_cast<std::size_t>(i)] ? Eigen::RowVector3d(N.row(i)) : m / len;
    result.normals.at<cv::Vec3f>(px) =
        cv::Vec3f(static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z()));
    result.albedo.at<float>(px) = static_cast<float>(len);
    const double rms = std::sqrt((I.row(i) - S.row(i) * lighting).squaredNorm() / static_cast<double>(q));
    result.residual.at<float>(px) = static_cast<float>(rms);
    result.solved.at<std::uint8_t>(px) = 255;
    ++solved;
  }
  std::vector<double> singular(static_cast<std::size_t>(std::min<Eigen::Index>(q, 2 * k)));
  for (std::size_t j = 0; j < singular.size(); ++j)
    singular[j] = std::sqrt(std::max(eig.eigenvalues()[q - 1 - static_cast<Eigen::Index>(j)], 0.0));
  result.parameters = options.to_json();
  result.parameters["fit"] = {{"prior_pixels", with_prior},  {"fit_pixels", rows.size()},
                              {"cost_linear", initial_cost}, {"cost_refined", final_cost},
                              {"evaluations", evaluations},  {"singular_values", singular}};
  const double kept_fraction = static_cast<double>(kept) / static_cast<double>(p);
  result.parameters["kept_prior"] = {{"pixels", kept},
                                     {"fraction", kept_fraction},
                                     {"cost_margin", margin},
                                     {"shading_model", model_from_prior ? "prior" : "fit"}};
  auto& s = result.summary;
  s.method = "shape-prior";
  s.pixels_in_mask = static_cast<std::size_t>(p);
  s.pixels_solved = solved;
  s.pixels_rejected_degenerate = degenerate;
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  s.settings = {{"k", k, fmt::format("k = {}", k)}};
  s.findings = {{"prior_fit_cost",
                 {{"linear", initial_cost}, {"refined", final_cost}, {"evaluations", evaluations}},
                 fmt::format("prior fit cost {:.4g} (linear) -> {:.4g} (refined, {} evaluations)",
                             initial_cost, final_cost, evaluations)}};
  if (options.keep_prior)
    s.findings.push_back({"kept_prior",
                          {{"pixels", kept}, {"fraction", kept_fraction}},
                          fmt::format("prior's normal kept at {:.1f}% of pixels", 100 * kept_fraction)});
  s.message = s.format_message();
  return result;
}

}  // namespace lightstage
