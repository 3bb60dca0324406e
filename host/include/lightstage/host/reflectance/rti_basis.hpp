#pragma once
// Per-pixel RTI reflectance models: a value under a distant light l is a
// linear combination of basis functions of l, fitted per pixel by least
// squares (docs/rti-formats.md gives the bases and their sources).
//   PTM (Malzbender et al. 2001): with (lu, lv) = (l.x, l.y),
//     C = a0 lu² + a1 lv² + a2 lu lv + a3 lu + a4 lv + a5
//   HSH (Gautron et al. 2004, as RTIViewer evaluates it), order 2 = 4 terms,
//     order 3 = 9 terms, of θ = acos(l.z), φ = atan2(l.y, l.x).
// One small interface for both: the basis, its size, a fit and an evaluation.

#include "lightstage/common/geometry.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace lightstage {

enum class RtiBasis { ptm, hsh2, hsh3 };

// "ptm", "hsh2", "hsh3"; throws InputError for anything else.
RtiBasis parse_rti_basis(const std::string& name);
const char* rti_basis_name(RtiBasis basis);
int rti_term_count(RtiBasis basis);

// The basis functions at one light (normalised here), rti_term_count values.
Eigen::VectorXd rti_weights(RtiBasis basis, const Vec3& light);

// Least-squares coefficients: `values` is pixels × lights (one channel),
// `lights` lights × 3; returns pixels × terms. Throws InputError when there
// are fewer lights than terms or the lights do not determine the fit.
Eigen::MatrixXf fit_rti(RtiBasis basis, const Eigen::MatrixXf& values, const Eigen::MatrixX3d& lights);

// pixels × 1: the model of `coefficients` (pixels × terms) under `light`.
Eigen::VectorXf evaluate_rti(RtiBasis basis, const Eigen::MatrixXf& coefficients, const Vec3& light);

}  // namespace lightstage
