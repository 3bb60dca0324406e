#pragma once
// Robust photometric stereo by low-rank matrix completion and recovery (Wu,
// Ganesh, Shi, Matsushita, Wang, Ma, ACCV 2010; ALGORITHMS.md "Robust
// family"). The observation matrix D (pixels × images) is split into A, of
// low rank (Lambertian: rank 3), plus E, sparse (highlights, cast shadows):
//     min ‖A‖_* + λ‖E‖₁  subject to  P_Ω(D) = P_Ω(A + E),
// Ω = the observations that are neither shadowed (≤ shadow_threshold) nor
// saturated — those are missing entries A fills in. Solved by the inexact
// augmented Lagrange multiplier method; then each pixel's normal is the least
// squares fit of its row of A to the known lights (all images).
//
// Memory: the whole matrix is never held at once. Pixels are processed in
// blocks of block_pixels to 2 × block_pixels rows of D (each block is itself
// low rank, so the decomposition is done per block, in parallel); a block
// costs about 5 × its rows × images doubles. λ = lambda_scale / √(the block's rows).
// Blocks are cut from runs of whole image rows (rpca_row_runs), so a band of
// rows that starts and ends where runs do is decomposed as in the whole image.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/solve_result.hpp"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <vector>

namespace lightstage {

struct RpcaOptions {
  double shadow_threshold = 1e-6;  // observations ≤ this are missing entries (≥ 0)
  int block_pixels = 2048;         // rows of D decomposed together (≥ 16)
  double lambda_scale = 1.0;       // λ = lambda_scale / √rows (Candès et al.: 1 / √max(n1, n2))
  int max_iterations = 500;        // ALM rounds
  double tolerance = 1e-7;         // stop when ‖P_Ω(D − A − E)‖_F / ‖P_Ω(D)‖_F < tolerance
  int min_observations = 3;        // a pixel with fewer in Ω is rejected (≥ 3)
  bool drop_saturated = true;
  int threads = 0;
  SolveProgress progress;

  void check() const;
  nlohmann::json to_json() const;
};

// Image rows grouped into the runs whose pixels rpca splits into blocks, from
// each row's pixel count: a run ends with the row that brings it to
// block_pixels pixels; a last run under half that joins the one before, and
// rows without pixels at the end join the last run. Returns each run's end row
// (exclusive), the last being the row count; one run when no row has a pixel.
// A run depends only on the rows above it, so the runs of rows [a, b), where a
// and b are run ends of the whole image, are the whole image's runs there.
std::vector<int> rpca_row_runs(const std::vector<std::size_t>& row_pixels, int block_pixels);

// What rpca's blocks take at once beside the observations: each of its
// threads decomposing a block of the largest size (2 × block_pixels rows).
std::size_t rpca_working_bytes(const RpcaOptions& options, std::size_t images);

// The summary's settings of an rpca solve: its blocks, their mean ALM rounds
// and the highest rank of A (also what bands of one solve make together).
std::vector<SolveFact> rpca_settings(std::size_t blocks, double mean_rounds, int max_rank);

SolveResult solve_rpca(const Observations& observations, const RpcaOptions& options = {});

}  // namespace lightstage
