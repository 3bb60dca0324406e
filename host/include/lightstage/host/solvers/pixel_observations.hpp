#pragma once
// One pixel's photometric-stereo data as every per-pixel solver core takes
// it: its own light matrix and its values at unit light. With distant lights
// every pixel gets Observations::lights; with near lights (LED positions
// known) each pixel gets its own directions, and its values are divided by
// the inverse-square gain (near_lights.hpp), so cores need not know which
// light model produced them; near_lights() says so where the noise differs
// (robust's refit).

#include "lightstage/host/radiometry.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace lightstage {

struct PixelObservations {
  Eigen::MatrixX3d lights;           // images × 3, unit, object -> light
  Eigen::VectorXd values;            // images, linear value at unit light
  std::vector<std::uint8_t> usable;  // images, 1 = finite and (unless kept) not saturated
  Eigen::VectorXd near_gains;  // images, the near lights' falloff the values were divided by; empty: distant

  Eigen::Index count() const { return values.size(); }
  bool near_lights() const { return near_gains.size() > 0; }
};

// Fills `out` for row `pixel` of `observations`. When `drop_saturated`,
// saturated observations are marked unusable.
void load_pixel(const Observations& observations, std::size_t pixel, bool drop_saturated,
                PixelObservations& out);

// Throws InputError (naming `who`) when the observation matrix, flags or
// near-light tables do not match the pixel and image counts.
void check_observations(const Observations& observations, const char* who);

}  // namespace lightstage
