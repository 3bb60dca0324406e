#include "lightstage/host/solvers/low_rank.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/solvers/pixel_observations.hpp"
#include "solvers/lambert_fit.hpp"
#include "solvers/pixel_driver.hpp"

#include <fmt/format.h>
#include <Eigen/Dense>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <numeric>
#include <utility>
#include <vector>

namespace lightstage {
namespace {

using Matrix = Eigen::MatrixXd;

// Growth of the penalty μ per round and its ceiling relative to the start
// (Lin, Chen, Ma's inexact ALM).
constexpr double kRho = 1.1;
constexpr double kMuCeiling = 1e7;

// Singular value thresholding through the images × images Gram matrix (there
// are far fewer images than pixels): X = U Σ Vᵀ, returns U max(Σ − τ, 0) Vᵀ
// = X V diag(max(σ − τ, 0) / σ) Vᵀ. Also returns the rank kept.
int shrink_singular_values(const Matrix& x, double tau, Matrix& out) {
  const Matrix gram = x.transpose() * x;
  Eigen::SelfAdjointEigenSolver<Matrix> eigen(gram);
  const Eigen::VectorXd sigma = eigen.eigenvalues().cwiseMax(0).cwiseSqrt();
  int rank = 0;
  for (Eigen::Index k = sigma.size() - 1; k >= 0 && sigma(k) > tau; --k) ++rank;
  if (rank == 0) {
    out.setZero(x.rows(), x.cols());
    return 0;
  }
  const Matrix v = eigen.eigenvectors().rightCols(rank);
  const Eigen::VectorXd factor =
      (sigma.tail(rank).array() - tau).cwiseQuotient(sigma.tail(rank).array()).matrix();
  out.noalias() = (x * v) * factor.asDiagonal() * v.transpose();
  return rank;
}

double spectral_norm(const Matrix& x) {
  const Matrix gram = x.transpose() * x;
  Eigen::SelfAdjointEigenSolver<Matrix> eigen(gram, Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(eigen.eigenvalues().maxCoeff(), 0.0));
}

struct BlockOutcome {
  std::size_t solved = 0, too_few = 0, degenerate = 0;
  int iterations = 0;
  int rank = 0;
};

// Decomposes rows [begin, end) of the observations and writes their maps.
BlockOutcome solve_block(const Observations& obs, const RpcaOptions& options, std::size_t begin,
                         std::size_t end, SolveResult& result) {
  BlockOutcome outcome;
  const auto rows = static_cast<Eigen::Index>(end - begin);
  const auto images = static_cast<Eigen::Index>(obs.image_count());
  Matrix d = Matrix::Zero(rows, images);
  Matrix omega = Matrix::Zero(rows, images);  // 1 = observed (in Ω)
  std::vector<std::uint8_t> enough(static_cast<std::size_t>(rows), 0);
  PixelObservations pixel;
  for (Eigen::Index r = 0; r < rows; ++r) {
    load_pixel(obs, begin + static_cast<std::size_t>(r), options.drop_saturated, pixel);
    int count = 0;
    for (Eigen::Index j = 0; j < images; ++j) {
      if (pixel.usable[static_cast<std::size_t>(j)] && pixel.values(j) > options.shadow_threshold) {
        d(r, j) = pixel.values(j);
        omega(r, j) = 1;
        ++count;
      }
    }
    enough[static_cast<std::size_t>(r)] = count >= options.min_observations ? 1 : 0;
  }
  const double d_norm = d.norm();
  Matrix a = Matrix::Zero(rows, images), e = Matrix::Zero(rows, images);
  if (d_norm > 0) {
    const double lambda =
        options.lambda_scale / std::sqrt(static_cast<double>(std::max<Eigen::Index>(rows, images)));
    const double norm_two = spectral_norm(d);
    Matrix y = d / std::max(norm_two, d.cwiseAbs().maxCoeff() / lambda);
    double mu = 1.25 / norm_two;
    const double mu_max = mu * kMuCeiling;
    Matrix t(rows, images), z(rows, images);
    for (int it = 0; it < options.max_iterations; ++it) {
      ++outcome.iterations;
      // E: soft threshold on Ω; outside Ω it takes whatever A leaves (no constraint there).
      t = d - a + y / mu;
      const double shrink = lambda / mu;
      e = omega.cwiseProduct((t.array().abs() - shrink).cwiseMax(0).matrix().cwiseProduct(t.cwiseSign())) +
          (1 - omega.array()).matrix().cwiseProduct(t);
      t = d - e + y / mu;
      outcome.rank = shrink_singular_values(t, 1 / mu, a);
      z = omega.cwiseProduct(d - a - e);
      y += mu * z;
      mu = std::min(mu * kRho, mu_max);
      if (z.norm() / d_norm < options.tolerance) break;
    }
  }
  // Normals: each pixel's row of A fitted to its lights over every image (A fills the missing ones).
  std::vector<Eigen::Index> all(static_cast<std::size_t>(images));
  std::iota(all.begin(), all.end(), Eigen::Index{0});
  for (Eigen::Index r = 0; r < rows; ++r) {
    const std::size_t p = begin + static_cast<std::size_t>(r);
    if (!enough[static_cast<std::size_t>(r)]) {
      ++outcome.too_few;
      continue;
    }
    load_pixel(obs, p, options.drop_saturated, pixel);  // its lights (per pixel with near lights)
    const Eigen::VectorXd row = a.row(r).transpose();
    Eigen::Vector3d s;
    if (!detail::lambert_fit(pixel.lights, row, all, s) || s.norm() < 1e-12) {
      ++outcome.degenerate;
      continue;
    }
    double squared = 0;
    double count = 0;
    for (Eigen::Index j = 0; j < images; ++j) {
      if (omega(r, j) == 0) continue;
      const double residual = pixel.lights.row(j).dot(s) - d(r, j);
      squared += residual * residual;
      ++count;
    }
    const Eigen::Vector3d n = s.normalized();
    const cv::Point& at = obs.pixels[p];
    result.normals.at<cv::Vec3f>(at) =
        cv::Vec3f(static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z()));
    result.albedo.at<float>(at) = static_cast<float>(s.norm());
    result.residual.at<float>(at) = static_cast<float>(std::sqrt(squared / count));
    result.solved.at<std::uint8_t>(at) = 255;
    ++outcome.solved;
  }
  return outcome;
}

}  // namespace

void RpcaOptions::check() const {
  detail::check_shadow_threshold("RpcaOptions", shadow_threshold);
  if (block_pixels < 16) fail("RpcaOptions.block_pixels: must be at least 16, got {}", block_pixels);
  if (!(lambda_scale > 0 && std::isfinite(lambda_scale)))
    fail("RpcaOptions.lambda_scale: must be positive, got {}", lambda_scale);
  if (max_iterations < 1) fail("RpcaOptions.max_iterations: must be at least 1, got {}", max_iterations);
  if (!(tolerance > 0 && std::isfinite(tolerance)))
    fail("RpcaOptions.tolerance: must be positive, got {}", tolerance);
  detail::check_min_observations("RpcaOptions", min_observations);
  detail::check_threads("RpcaOptions", threads);
}

nlohmann::json RpcaOptions::to_json() const {
  return {{"shadow_threshold", shadow_threshold},
          {"block_pixels", block_pixels},
          {"lambda_scale", lambda_scale},
          {"max_iterations", max_iterations},
          {"tolerance", tolerance},
          {"min_observations", min_observations},
          {"drop_saturated", drop_saturated},
          {"threads", threads}};
}

std::size_t rpca_working_bytes(const RpcaOptions& options, std::size_t images) {
  // D, Ω, A, E, Y and two temporaries of rows × images doubles (solve_block).
  constexpr std::size_t kMatrices = 7;
  const auto rows = 2 * static_cast<std::size_t>(options.block_pixels);
  return static_cast<std::size_t>(resolve_threads(options.threads)) * kMatrices * rows * images *
         sizeof(double);
}

std::vector<SolveFact> rpca_settings(std::size_t blocks, double mean_rounds, int max_rank) {
  return {{"blocks", blocks, fmt::format("{} blocks", blocks)},
          {"iterations", mean_rounds, fmt::format("{:.0f} ALM rounds per block", mean_rounds)},
          {"rank", max_rank, fmt::format("rank of A at most {}", max_rank)}};
}

std::vector<int> rpca_row_runs(const std::vector<std::size_t>& row_pixels, int block_pixels) {
  const auto block = static_cast<std::size_t>(std::max(block_pixels, 1));
  std::vector<int> ends;
  std::size_t pending = 0;
  for (std::size_t y = 0; y < row_pixels.size(); ++y) {
    pending += row_pixels[y];
    if (pending < block) continue;
    ends.push_back(static_cast<int>(y + 1));
    pending = 0;
  }
  const int rows = static_cast<int>(row_pixels.size());
  if (ends.empty() || (pending > 0 && pending >= block / 2))
    ends.push_back(rows);
  else
    ends.back() = rows;  // a short last run, or rows without pixels, join the run before
  return ends;
}

SolveResult solve_rpca(const Observations& observations, const RpcaOptions& options) {
  options.check();
  check_observations(observations, "rpca");
  const auto start = std::chrono::steady_clock::now();
  SolveResult result;
  const cv::Size size = observations.size;
  detail::allocate_result_maps(size, result);
  // Each run of rows split into equal blocks of block_pixels to twice that (a short last run less): the split
  // depends on the rows' pixel counts only, so results do not depend on the thread count or on bands cut at
  // run ends.
  const std::size_t pixels = observations.pixel_count();
  std::vector<std::size_t> row_pixels(static_cast<std::size_t>(size.height), 0);
  for (const cv::Point& at : observations.pixels) ++row_pixels[static_cast<std::size_t>(at.y)];
  const auto block = static_cast<std::size_t>(options.block_pixels);
  std::vector<std::pair<std::size_t, std::size_t>> ranges;  // [begin, end) of each block
  std::size_t run_begin = 0;
  int row = 0;
  for (const int run_end : rpca_row_runs(row_pixels, options.block_pixels)) {
    std::size_t run_pixels = 0;
    for (; row < run_end; ++row) run_pixels += row_pixels[static_cast<std::size_t>(row)];
    const std::size_t pieces = std::max<std::size_t>(run_pixels / block, run_pixels > 0 ? 1 : 0);
    for (std::size_t k = 0; k < pieces; ++k)
      ranges.emplace_back(run_begin + run_pixels * k / pieces, run_begin + run_pixels * (k + 1) / pieces);
    run_begin += run_pixels;
  }
  const std::size_t blocks = ranges.size();
  std::vector<BlockOutcome> outcomes(blocks);
  parallel_for(static_cast<int>(blocks), options.threads, [&](int b) {
    const auto [begin, end] = ranges[static_cast<std::size_t>(b)];
    outcomes[static_cast<std::size_t>(b)] = solve_block(observations, options, begin, end, result);
    if (options.progress) options.progress(end - begin);
  });
  SolveSummary& summary = result.summary;
  summary.method = "rpca";
  summary.pixels_in_mask = pixels;
  double iterations = 0;
  int max_rank = 0;
  for (const auto& o : outcomes) {
    summary.pixels_solved += o.solved;
    summary.pixels_rejected_too_few_observations += o.too_few;
    summary.pixels_rejected_degenerate += o.degenerate;
    iterations += o.iterations;
    max_rank = std::max(max_rank, o.rank);
  }
  if (blocks > 0) iterations /= static_cast<double>(blocks);
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.parameters = options.to_json();
  summary.settings = rpca_settings(blocks, iterations, max_rank);
  summary.message = summary.format_message();
  return result;
}

}  // namespace lightstage
