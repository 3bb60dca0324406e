#pragma once
// Four pixels side by side, one in each lane of a vector of doubles. l2 and
// the confidence spend their time in sums over a pixel's lights (under near
// lights every pixel has its own directions); with a pixel per lane each
// light is one vector step for four pixels, and no lane's sums are ever
// added across lanes.
//
// Each lane's arithmetic is what one pixel's would be alone, in a fixed
// order: a pixel's sums take its even lights into one set and its odd lights
// into another, added at the end (for_each_light_in_two_sets), so a pixel's
// answer is the same float in any lane, beside any neighbours, in any band.

#include "lightstage/host/radiometry.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace lightstage {

inline constexpr std::size_t kPixelLanes = 4;
// Aligned to its size, which a baseline x86-64 build would not give it (its
// widest alignment is 16) and the AVX2 build's aligned loads need.
using PixelLanes =
    double __attribute__((vector_size(kPixelLanes * sizeof(double)), aligned(kPixelLanes * sizeof(double))));
using PixelMask = decltype(PixelLanes{} < PixelLanes{});
static_assert(alignof(PixelLanes) == sizeof(PixelLanes));  // masks are never stored

// Per-image lanes, each aligned to its size (a standard container of
// PixelLanes would drop the type's alignment attribute).
class LaneBuffer {
 public:
  void resize(std::size_t size) { slots_.resize(size); }
  void clear() { slots_.clear(); }
  std::size_t size() const { return slots_.size(); }
  bool empty() const { return slots_.empty(); }
  PixelLanes* data() { return slots_.empty() ? nullptr : &slots_.front().lanes; }
  const PixelLanes* data() const { return slots_.empty() ? nullptr : &slots_.front().lanes; }
  PixelLanes& operator[](std::size_t i) { return slots_[i].lanes; }
  const PixelLanes& operator[](std::size_t i) const { return slots_[i].lanes; }

 private:
  struct alignas(sizeof(PixelLanes)) Slot {
    PixelLanes lanes;
  };
  std::vector<Slot> slots_;
};

// A vector wider than the baseline's registers never crosses a call by
// value (its ABI differs by instruction set, and GCC 12 fails to build such a
// call into functions made for several, LIGHTSTAGE_SIMD_CLONES): functions
// take and give them by reference. `x - PixelLanes{}` gives x in every lane
// (−0 too), and `x - x == zero` marks the lanes where x is finite.

// Up to kPixelLanes pixels' lights and observations, image by image. One
// per thread and solve: distant lights are filled in once.
struct LightLanes {
  std::size_t used = 0;                    // lanes in use; the rest repeat the first pixel
  LaneBuffer x, y, z;                      // per image: unit direction, object -> light
  LaneBuffer gain;                         // per image: the near light's fall-off gain; empty: distant lights
  LaneBuffer observed;                     // per image: the observed value (a float, widened)
  LaneBuffer unsaturated;                  // per image: 0 where flagged saturated, else 1
  const double* distant_lights = nullptr;  // the distant lights x, y and z were filled from (once)

  std::size_t images() const { return observed.size(); }
  bool near_lights() const { return !gain.empty(); }
};

// Loads pixels[0, count) (1 ≤ count ≤ kPixelLanes) of `observations`, with
// their near lights' directions and gains where it has near lights
// (`reference`: near_light_reference), the same doubles
// near_light_directions gives.
void load_light_lanes(const Observations& observations, const Eigen::VectorXd& reference,
                      const std::size_t* pixels, std::size_t count, LightLanes& out);

// Calls add(set, j) for every image j in order: set 0 for the even images,
// 1 for the odd ones (a constant in each call, so sums stay in registers).
template <typename Add>
[[gnu::always_inline]] inline void for_each_light_in_two_sets(std::size_t images, Add&& add) {
  std::size_t j = 0;
  for (; j + 2 <= images; j += 2) {
    add(0, j);
    add(1, j + 1);
  }
  if (j < images) add(0, j);  // the last of an odd count is even
}

// Σ l lᵀ and Σ v l over the lights a mask keeps, per lane, in two sets (even
// and odd lights). A light left out adds exact zeros: its value is not read.
struct NormalEquationLanes {
  PixelLanes gram[2][6] = {};    // Σ l lᵀ, upper triangle (xx, xy, xz, yy, yz, zz)
  PixelLanes moment[2][3] = {};  // Σ v l

  [[gnu::always_inline]] void add(int set, const PixelMask& keep, const PixelLanes& lx, const PixelLanes& ly,
                                  const PixelLanes& lz, const PixelLanes& value) {
    const PixelLanes zero = {};
    const PixelLanes x = keep ? lx : zero, y = keep ? ly : zero, z = keep ? lz : zero;
    const PixelLanes v = keep ? value : zero;
    PixelLanes* g = gram[set];
    g[0] += x * lx;
    g[1] += x * ly;
    g[2] += x * lz;
    g[3] += y * ly;
    g[4] += y * lz;
    g[5] += z * lz;
    PixelLanes* m = moment[set];
    m[0] += x * v;
    m[1] += y * v;
    m[2] += z * v;
  }

  Eigen::Matrix3d gram_matrix(std::size_t lane) const { return symmetric(gram, lane); }
  Eigen::Vector3d moment_vector(std::size_t lane) const {
    return {moment[0][0][lane] + moment[1][0][lane], moment[0][1][lane] + moment[1][1][lane],
            moment[0][2][lane] + moment[1][2][lane]};
  }

  // The symmetric matrix of lane `lane` of two sets of an upper triangle.
  static Eigen::Matrix3d symmetric(const PixelLanes (&upper)[2][6], std::size_t lane) {
    double v[6];
    for (int k = 0; k < 6; ++k) v[k] = upper[0][k][lane] + upper[1][k][lane];
    Eigen::Matrix3d out;
    out << v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5];
    return out;
  }
};

}  // namespace lightstage
