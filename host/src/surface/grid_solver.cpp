#include "surface/grid_solver.hpp"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <memory>

namespace lightstage::surface {

GridSystem::GridSystem(int rows_, int cols_)
    : rows(rows_),
      cols(cols_),
      inside(static_cast<std::size_t>(rows_) * cols_, 0),
      wx(inside.size(), 0.0),
      wy(inside.size(), 0.0),
      rhs(inside.size(), 0.0) {}

void GridSystem::add_edge(int r, int c, bool horizontal, double w, double g) {
  const std::size_t i = index(r, c);
  const std::size_t j = horizontal ? index(r, c + 1) : index(r + 1, c);
  assert(inside[i] && inside[j]);
  (horizontal ? wx : wy)[i] += w;
  // d/dx_i of w (x_j − x_i − g)² = −2w(x_j − x_i − g): the g part moves to b.
  rhs[i] -= w * g;
  rhs[j] += w * g;
}

void GridSystem::add_data(int r, int c, double d, double z) {
  const std::size_t i = index(r, c);
  if (diag.empty()) diag.assign(inside.size(), 0.0);
  diag[i] += d;
  rhs[i] += d * z;
}

namespace {

// One level of the hierarchy: the operator only (right-hand sides travel).
// The finest level reads the GridSystem's arrays in place (at 24 Mpx a copy
// is 600 MB); coarser levels own theirs.
struct Level {
  int rows = 0, cols = 0;
  const std::uint8_t* inside = nullptr;
  const double *wx = nullptr, *wy = nullptr;
  const double* diag = nullptr;  // nullptr = all 0
  // 1 / (d_i + Σ w), 0 where the row is empty. Float: it only scales the
  // smoother's steps, and at 24 Mpx the finest level's is then 100 MB less.
  std::vector<float> inv_total;

  std::size_t size() const { return static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols); }
  double diag_at(std::size_t i) const { return diag ? diag[i] : 0.0; }

  // Coarse levels: the arrays the pointers above read (a moved vector keeps its buffer).
  std::vector<std::uint8_t> own_inside;
  std::vector<double> own_wx, own_wy, own_diag;
};

void finish_level(Level& l) {
  l.inv_total.assign(l.size(), 0.0);
  for (int r = 0; r < l.rows; ++r) {
    for (int c = 0; c < l.cols; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * l.cols + c;
      if (!l.inside[i]) continue;
      double t = l.diag_at(i) + l.wx[i] + l.wy[i];
      if (c > 0) t += l.wx[i - 1];
      if (r > 0) t += l.wy[i - l.cols];
      l.inv_total[i] = t > 0 ? static_cast<float>(1.0 / t) : 0.0f;
    }
  }
}

// (A x)_i for the pixel i = (r, c), which is inside.
double apply_at(const Level& l, const std::vector<double>& x, int r, int c, std::size_t i) {
  const int cols = l.cols;
  double v = l.diag_at(i) * x[i];
  if (l.wx[i] != 0) v += l.wx[i] * (x[i] - x[i + 1]);
  if (l.wy[i] != 0) v += l.wy[i] * (x[i] - x[i + cols]);
  if (c > 0 && l.wx[i - 1] != 0) v += l.wx[i - 1] * (x[i] - x[i - 1]);
  if (r > 0 && l.wy[i - cols] != 0) v += l.wy[i - cols] * (x[i] - x[i - cols]);
  return v;
}

// y = A x.
void apply(const Level& l, const std::vector<double>& x, std::vector<double>& y) {
  y.assign(l.size(), 0.0);
  for (int r = 0; r < l.rows; ++r) {
    for (int c = 0; c < l.cols; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * l.cols + c;
      if (l.inside[i]) y[i] = apply_at(l, x, r, c, i);
    }
  }
}

// One Gauss–Seidel sweep, forward or backward (the pair keeps the V-cycle symmetric).
void gauss_seidel(const Level& l, const std::vector<double>& b, std::vector<double>& x, bool forward) {
  const int cols = l.cols;
  const long n = static_cast<long>(l.size());
  for (long k = 0; k < n; ++k) {
    const std::size_t i = static_cast<std::size_t>(forward ? k : n - 1 - k);
    if (l.inv_total[i] == 0) continue;
    const int c = static_cast<int>(i % static_cast<std::size_t>(cols));
    double s = b[i];
    if (l.wx[i] != 0) s += l.wx[i] * x[i + 1];
    if (l.wy[i] != 0) s += l.wy[i] * x[i + cols];
    if (c > 0 && l.wx[i - 1] != 0) s += l.wx[i - 1] * x[i - 1];
    if (i >= static_cast<std::size_t>(cols) && l.wy[i - cols] != 0) s += l.wy[i - cols] * x[i - cols];
    x[i] = s * l.inv_total[i];
  }
}

// Galerkin coarse grid for piecewise-constant aggregation over 2×2 blocks:
// edges inside a block vanish, edges across blocks add up, diagonals add up.
Level coarsen(const Level& f) {
  Level c;
  c.rows = (f.rows + 1) / 2;
  c.cols = (f.cols + 1) / 2;
  const std::size_t n = static_cast<std::size_t>(c.rows) * c.cols;
  std::vector<std::uint8_t>& inside = c.own_inside;
  std::vector<double>&wx = c.own_wx, &wy = c.own_wy, &diag = c.own_diag;
  inside.assign(n, 0);
  wx.assign(n, 0.0);
  wy.assign(n, 0.0);
  diag.assign(n, 0.0);
  for (int r = 0; r < f.rows; ++r) {
    for (int col = 0; col < f.cols; ++col) {
      const std::size_t i = static_cast<std::size_t>(r) * f.cols + col;
      if (!f.inside[i]) continue;
      const std::size_t ci = static_cast<std::size_t>(r / 2) * c.cols + col / 2;
      inside[ci] = 1;
      diag[ci] += f.diag_at(i);
      if (f.wx[i] != 0 && (col % 2) == 1) wx[ci] += f.wx[i];
      if (f.wy[i] != 0 && (r % 2) == 1) wy[ci] += f.wy[i];
    }
  }
  c.inside = inside.data();
  c.wx = wx.data();
  c.wy = wy.data();
  c.diag = diag.data();
  finish_level(c);
  return c;
}

class Multigrid {
 public:
  explicit Multigrid(Level fine) {
    levels_.push_back(std::move(fine));
    finish_level(levels_.back());
    // Coarsen until the grid is small enough for a direct solve.
    while (unknowns(levels_.back()) > kDirectUnknowns && levels_.back().rows > 2 && levels_.back().cols > 2)
      levels_.push_back(coarsen(levels_.back()));
    build_direct(levels_.back());
    work_b_.resize(levels_.size());
    work_x_.resize(levels_.size());
  }

  const Level& fine() const { return levels_.front(); }

  // z ≈ A⁻¹ r: one symmetric V-cycle from zero.
  void precondition(const std::vector<double>& r, std::vector<double>& z) { cycle(0, r, z); }

 private:
  static constexpr std::size_t kDirectUnknowns = 3000;
  static constexpr int kSweeps = 2;

  static std::size_t unknowns(const Level& l) {
    return static_cast<std::size_t>(std::count(l.inside, l.inside + l.size(), 1));
  }

  void build_direct(const Level& l) {
    direct_index_.assign(l.size(), -1);
    int n = 0;
    for (std::size_t i = 0; i < l.size(); ++i)
      if (l.inside[i]) direct_index_[i] = n++;
    std::vector<Eigen::Triplet<double>> t;
    double max_total = 0;
    for (int r = 0; r < l.rows; ++r) {
      for (int c = 0; c < l.cols; ++c) {
        const std::size_t i = static_cast<std::size_t>(r) * l.cols + c;
        if (!l.inside[i]) continue;
        const int a = direct_index_[i];
        t.emplace_back(a, a, l.diag_at(i));
        auto edge = [&](std::size_t j, double w) {
          if (w == 0) return;
          const int b = direct_index_[j];
          t.emplace_back(a, a, w);
          t.emplace_back(b, b, w);
          t.emplace_back(a, b, -w);
          t.emplace_back(b, a, -w);
        };
        if (c + 1 < l.cols) edge(i + 1, l.wx[i]);
        if (r + 1 < l.rows) edge(i + static_cast<std::size_t>(l.cols), l.wy[i]);
        if (l.inv_total[i] > 0) max_total = std::max(max_total, 1.0 / l.inv_total[i]);
      }
    }
    // A tiny shift makes a pure Laplacian (singular: constants per component)
    // factorisable; it only picks one of the equivalent solutions.
    const double shift = 1e-10 * std::max(max_total, 1e-300);
    for (int a = 0; a < n; ++a) t.emplace_back(a, a, shift);
    Eigen::SparseMatrix<double> m(n, n);
    m.setFromTriplets(t.begin(), t.end());
    direct_ = std::make_unique<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>>(m);
    direct_n_ = n;
  }

  void solve_direct(const Level& l, const std::vector<double>& b, std::vector<double>& x) {
    Eigen::VectorXd rhs(direct_n_);
    for (std::size_t i = 0; i < l.size(); ++i)
      if (direct_index_[i] >= 0) rhs[direct_index_[i]] = b[i];
    const Eigen::VectorXd sol = direct_->solve(rhs);
    x.assign(l.size(), 0.0);
    for (std::size_t i = 0; i < l.size(); ++i)
      if (direct_index_[i] >= 0) x[i] = sol[direct_index_[i]];
  }

  // x ≈ A_k⁻¹ b on level k.
  void cycle(std::size_t k, const std::vector<double>& b, std::vector<double>& x) {
    const Level& l = levels_[k];
    if (k + 1 == levels_.size()) {
      solve_direct(l, b, x);
      return;
    }
    x.assign(l.size(), 0.0);
    for (int s = 0; s < kSweeps; ++s) gauss_seidel(l, b, x, true);
    // Restrict the residual (sum over each 2×2 block: Pᵀ), computed where it is
    // summed: a residual vector would be another 8 bytes a pixel.
    const Level& c = levels_[k + 1];
    std::vector<double>& cb = work_b_[k + 1];
    cb.assign(c.size(), 0.0);
    for (int r = 0; r < l.rows; ++r) {
      for (int col = 0; col < l.cols; ++col) {
        const std::size_t i = static_cast<std::size_t>(r) * l.cols + col;
        if (l.inside[i])
          cb[static_cast<std::size_t>(r / 2) * c.cols + col / 2] += b[i] - apply_at(l, x, r, col, i);
      }
    }
    cycle(k + 1, cb, work_x_[k + 1]);
    // Prolong (copy the block value: P). Plain aggregation under-corrects
    // smooth errors; the over-relaxation factor is the usual remedy.
    const std::vector<double>& cx = work_x_[k + 1];
    for (int r = 0; r < l.rows; ++r) {
      for (int col = 0; col < l.cols; ++col) {
        const std::size_t i = static_cast<std::size_t>(r) * l.cols + col;
        if (l.inside[i]) x[i] += kCoarseScale * cx[static_cast<std::size_t>(r / 2) * c.cols + col / 2];
      }
    }
    for (int s = 0; s < kSweeps; ++s) gauss_seidel(l, b, x, false);
  }

  static constexpr double kCoarseScale = 1.6;

  std::vector<Level> levels_;
  std::vector<std::vector<double>> work_b_, work_x_;
  std::vector<int> direct_index_;
  int direct_n_ = 0;
  std::unique_ptr<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>> direct_;
};

double dot(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
  return s;
}

}  // namespace

GridSolveStats solve_grid(const GridSystem& system, std::vector<double>& x, double tolerance,
                          int max_iterations, const std::function<void(double)>& on_iteration) {
  Level fine;
  fine.rows = system.rows;
  fine.cols = system.cols;
  fine.inside = system.inside.data();
  fine.wx = system.wx.data();
  fine.wy = system.wy.data();
  fine.diag = system.diag.empty() ? nullptr : system.diag.data();
  const std::size_t n = fine.size();
  if (x.size() != n) x.assign(n, 0.0);
  double b_squared = 0;  // b: the right-hand side, 0 outside
  for (std::size_t i = 0; i < n; ++i) {
    if (!fine.inside[i]) x[i] = 0;
    if (fine.inside[i]) b_squared += system.rhs[i] * system.rhs[i];
  }

  GridSolveStats stats;
  const double b_norm = std::sqrt(b_squared);
  if (b_norm == 0) {
    std::fill(x.begin(), x.end(), 0.0);
    stats.converged = true;
    return stats;
  }
  Multigrid mg(std::move(fine));
  const Level& l = mg.fine();
  std::vector<double> r(n), z, p, q;
  apply(l, x, q);
  for (std::size_t i = 0; i < n; ++i) r[i] = fine.inside[i] ? system.rhs[i] - q[i] : 0.0;
  mg.precondition(r, z);
  p = z;
  double rz = dot(r, z);
  for (int it = 0; it < max_iterations; ++it) {
    stats.relative_residual = std::sqrt(dot(r, r)) / b_norm;
    if (on_iteration) on_iteration(stats.relative_residual);
    if (stats.relative_residual <= tolerance) {
      stats.converged = true;
      break;
    }
    apply(l, p, q);
    const double pq = dot(p, q);
    if (!(pq > 0)) break;  // only the null space is left (singular A)
    const double alpha = rz / pq;
    for (std::size_t i = 0; i < n; ++i) {
      x[i] += alpha * p[i];
      r[i] -= alpha * q[i];
    }
    mg.precondition(r, z);
    const double rz_next = dot(r, z);
    const double beta = rz_next / rz;
    rz = rz_next;
    for (std::size_t i = 0; i < n; ++i) p[i] = z[i] + beta * p[i];
    stats.iterations = it + 1;
  }
  stats.relative_residual = std::sqrt(dot(r, r)) / b_norm;
  stats.converged = stats.converged || stats.relative_residual <= tolerance;
  return stats;
}

}  // namespace lightstage::surface
