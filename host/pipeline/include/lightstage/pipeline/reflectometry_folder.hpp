#pragma once
// Reflectometry of a stack whose normals are known (dissertation 3.5): one
// BRDF for the whole object — Lambert, bilinear, biquadratic, bicubic and
// Cook–Torrance — each fitted to the stack's observations.

#include "lightstage/host/reflectance/reflectometry.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <vector>

namespace lightstage::pipeline {

struct ReflectometrySettings {
  std::filesystem::path input;    // a stack folder
  std::filesystem::path normals;  // a normal map; empty = the stack's Normal_gt.png
  SampleOptions samples;
  bool clamp_to_one = true;
  std::filesystem::path out;  // folder for reflectance.json; empty = nothing written
};

struct ReflectometryReport {
  std::size_t samples = 0;
  std::vector<ReflectanceFit> fits;
  nlohmann::json json;  // what reflectance.json holds
};

// Writes out/reflectance.json when `out` is set. Throws InputError naming
// --normals when the stack has no ground truth and none is given, --out when
// it is the stack folder or inside it.
ReflectometryReport fit_stack_reflectance(const ReflectometrySettings& settings);

}  // namespace lightstage::pipeline
