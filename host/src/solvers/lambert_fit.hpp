#pragma once
// Weighted Lambertian least squares on a subset of one pixel's observations,
// shared by the robust, bi-polynomial and monotonic cores.

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <vector>

namespace lightstage::detail {

// Smallest / largest eigenvalue of LᵀWL below which the lights count as coplanar.
inline constexpr double kCoplanarEigenvalueRatio = 1e-6;

// s = argmin Σ_{j ∈ kept} w_j (l_j·s − i_j)², w_j = 1 without weights.
// Returns false when the kept lights are (nearly) coplanar.
inline bool lambert_fit(const Eigen::MatrixX3d& lights, const Eigen::VectorXd& values,
                        const std::vector<Eigen::Index>& kept, Eigen::Vector3d& s,
                        const Eigen::VectorXd* weights = nullptr) {
  Eigen::Matrix3d gram = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (const Eigen::Index j : kept) {
    const double w = weights != nullptr ? (*weights)(j) : 1.0;
    const Eigen::Vector3d l = lights.row(j).transpose();
    gram.noalias() += w * l * l.transpose();
    rhs.noalias() += w * values(j) * l;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(gram);
  const Eigen::Vector3d lambda = eigen.eigenvalues();
  if (!(lambda(0) > kCoplanarEigenvalueRatio * lambda(2))) return false;
  const Eigen::Matrix3d& v = eigen.eigenvectors();
  s = v * (v.transpose() * rhs).cwiseQuotient(lambda);
  return s.allFinite();
}

}  // namespace lightstage::detail
