#pragma once
// A symmetric positive (semi-)definite system on a pixel grid, the shape every
// surface problem here takes (integration, fusion, reweighted integration):
//     minimise Σ_edges w_e (x_j − x_i − g_e)² + Σ_i d_i (x_i − z_i)²
// whose normal equations are A x = b with A a weighted graph Laplacian of the
// 4-neighbour grid plus diag(d). Solved by conjugate gradients preconditioned
// with an aggregation multigrid V-cycle (2×2 pixel blocks, Galerkin coarse
// grids, Gauss–Seidel smoothing, a direct solve on the coarsest grid): Eigen's
// sparse Cholesky takes >10 s at 1 Mpx on a 2D grid, this takes ~1 s.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace lightstage::surface {

struct GridSystem {
  int rows = 0, cols = 0;
  std::vector<std::uint8_t> inside;  // rows·cols, 1 = unknown
  // Edge weights, index r·cols + c: wx joins (r, c)–(r, c+1), wy joins (r, c)–(r+1, c).
  // Must be 0 unless both ends are inside.
  std::vector<double> wx, wy;
  std::vector<double> diag;  // d_i ≥ 0; empty until add_data (pure integration has none)
  std::vector<double> rhs;   // b

  GridSystem(int rows, int cols);
  std::size_t index(int r, int c) const { return static_cast<std::size_t>(r) * cols + c; }
  // Adds w (x_j − x_i − g)² for the edge from pixel i to its right (horizontal)
  // or lower (vertical) neighbour j.
  void add_edge(int r, int c, bool horizontal, double w, double g);
  // Adds d (x_i − z)².
  void add_data(int r, int c, double d, double z);
};

struct GridSolveStats {
  int iterations = 0;
  double relative_residual = 0;
  bool converged = false;
};

// Solves A x = b to ‖b − A x‖ ≤ tolerance · ‖b‖; `x` holds the initial guess
// (resized and zeroed when its size is wrong) and receives the solution, 0
// outside. A singular A (pure integration) is fine: the solution is then one
// of the minimisers; callers fix the additive constant. `on_iteration`, when
// set, receives the relative residual before every iteration.
GridSolveStats solve_grid(const GridSystem& system, std::vector<double>& x, double tolerance = 1e-7,
                          int max_iterations = 500,
                          const std::function<void(double relative_residual)>& on_iteration = {});

}  // namespace lightstage::surface
