#pragma once
// What `solve` checks around a method so that it never prints a number it
// cannot stand behind: lights that cannot determine a normal are an error
// before solving; a method used outside its assumptions is a warning; and
// normals that face away from an orthographic camera (z < 0, which no
// visible surface has) are clamped to the horizon and counted.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/solve_result.hpp"

#include <cstddef>
#include <string>
#include <vector>

namespace lightstage::pipeline {

// Throws InputError when the light directions span fewer than three
// dimensions (identical lights: rank 1; lights in one plane through the
// object, e.g. along one arc: rank 2), naming the rank and the cause.
void check_light_rank(const Observations& observations);

// The light cone: the largest angle of a light from the view axis, degrees.
double light_cone_deg(const Observations& observations);

// One line per assumption `method` makes that the lights break: monotonic
// with a narrow light cone (auto: a note that it then drops its monotonic
// candidate), the bi-polynomial methods (and auto) with under
// kMinBipolynomialLights lights, every general method with a 12-light-like
// set (under kFewLights).
inline constexpr int kMinBipolynomialLights = 50;
inline constexpr int kFewLights = 20;
inline constexpr double kMonotonicMinConeDeg = 60;
std::vector<std::string> method_warnings(const std::string& method, const Observations& observations);

// Sets z = 0 on every solved normal with z < 0 (keeping its azimuth;
// renormalised; one pointing straight away becomes the view direction) and
// returns how many there were.
std::size_t clamp_facing_away(SolveResult& result);

}  // namespace lightstage::pipeline
