#pragma once
// A pixel's 3×3 normal equations, Σ l lᵀ and Σ v l over the lights a mask
// keeps, summed two lights at a time in a vector's lanes (DoublePair). A
// light left out adds exact zeros: its value is not read (it may not be
// finite), only its direction.

#include "lightstage/common/double_pair.hpp"

#include <Eigen/Core>

namespace lightstage {

using PairMask = decltype(DoublePair{} != DoublePair{});

// The symmetric matrix of the lane sums of its upper triangle (xx, xy, xz, yy, yz, zz).
inline Eigen::Matrix3d symmetric_from_pairs(const DoublePair* upper) {
  const double xx = lane_sum(upper[0]), xy = lane_sum(upper[1]), xz = lane_sum(upper[2]),
               yy = lane_sum(upper[3]), yz = lane_sum(upper[4]), zz = lane_sum(upper[5]);
  Eigen::Matrix3d out;
  out << xx, xy, xz, xy, yy, yz, xz, yz, zz;
  return out;
}

struct NormalEquationPairs {
  DoublePair gram[6] = {};    // Σ l lᵀ, upper triangle
  DoublePair moment[3] = {};  // Σ v l

  void add(const PairMask keep, const DoublePair lx, const DoublePair ly, const DoublePair lz,
           const DoublePair value) {
    const DoublePair zero = {};
    const DoublePair x = keep ? lx : zero, y = keep ? ly : zero, z = keep ? lz : zero;
    const DoublePair v = keep ? value : zero;
    gram[0] += x * lx;
    gram[1] += x * ly;
    gram[2] += x * lz;
    gram[3] += y * ly;
    gram[4] += y * lz;
    gram[5] += z * lz;
    moment[0] += x * v;
    moment[1] += y * v;
    moment[2] += z * v;
  }

  Eigen::Matrix3d gram_matrix() const { return symmetric_from_pairs(gram); }
  Eigen::Vector3d moment_vector() const {
    return {lane_sum(moment[0]), lane_sum(moment[1]), lane_sum(moment[2])};
  }
};

}  // namespace lightstage
