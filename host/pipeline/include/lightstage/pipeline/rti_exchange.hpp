#pragma once
// RTI exchange, stack-folder to file and back (docs/rti-formats.md):
//   export_rti      a stack folder -> a PTM 1.2 file or an HSH .rti file
//   rti_holdout     leave-one-light-out relighting error of PTM, HSH and l2
//   import_rti      a folder of photographs plus an .lp file -> a stack folder

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

namespace lightstage::pipeline {

struct ExportSettings {
  std::filesystem::path input;  // a stack folder
  std::filesystem::path out;    // the file to write; must not exist
  std::string format = "ptm";   // ptm | hsh
  std::string colour = "lrgb";  // PTM only: lrgb | rgb
  int hsh_order = 3;            // HSH only: 2 (4 terms) | 3 (9 terms)
};

// Fits the stack and writes the file; returns a summary (format, size, terms).
// Throws InputError naming the flag, the stack file or the existing output.
nlohmann::json export_rti(const ExportSettings& settings);

struct HoldoutSettings {
  std::filesystem::path input;  // a stack folder
  int held_out = 12;            // lights held out one at a time, evenly spaced in the stack's order
};

// For each model (ptm, hsh2, hsh3, l2): fit on all lights but one, relight at
// that one, and compare with its photo on the object (mask) pixels, using
// radiometry.hpp's grey values: relative RMSE = ‖relit − photo‖ / ‖photo‖,
// then the mean over the held-out lights. Returns
// {"held_out": [...indices], "models": {"ptm": {"relative_rmse": ..., "per_light": [...]}, ...}}.
nlohmann::json rti_holdout(const HoldoutSettings& settings);

struct ImportSettings {
  std::filesystem::path input;     // folder of JPEG / PNG / TIFF photographs
  std::filesystem::path lp;        // empty = the one .lp file in `input`
  std::filesystem::path response;  // empty = sRGB curve for 8-bit images; else a `camera response` JSON
  std::filesystem::path out;       // stack folder to create; must be absent or empty
};

// Reads the .lp, finds each image it names in `input` (by its last path
// component), linearises it (io/rti_import.hpp) and writes a stack folder
// (docs/stack-format.md): 16-bit PNG frames, light_directions.txt from the
// .lp, a manifest saying where it came from. Returns the manifest's "import"
// entry. Throws InputError naming the .lp line, the image or --out.
nlohmann::json import_rti(const ImportSettings& settings);

}  // namespace lightstage::pipeline
