#pragma once
// Relighting a solve folder into a folder of images: one 16-bit PNG per light
// (relit_000.png, ...; value = min(v / scale, 1) · 65535; RGB when the solve
// was of a colour stack, reflectance/relight.hpp) and relight.json.

#include "lightstage/common/geometry.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <vector>

namespace lightstage::pipeline {

struct RelightSettings {
  std::filesystem::path input;  // a solve folder
  std::filesystem::path out;
  std::vector<Vec3> lights;  // object -> light, need not be unit
  double scale =
      0;  // value mapped to white; 0 = the 99.5th percentile of all frames' object pixels (every channel)
  bool grey = false;  // grey images from a colour result
};

// Returns relight.json as written. Throws InputError naming the file or light.
nlohmann::json relight_folder(const RelightSettings& settings);

}  // namespace lightstage::pipeline
