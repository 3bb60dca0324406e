#pragma once
// RTI exchange, stack-folder to file and back (docs/rti-formats.md):
//   export_rti      a stack (or a solve of one) -> a PTM 1.2 file, an HSH .rti
//                   file or a relight web folder
//   rti_holdout     leave-one-light-out relighting error of PTM, HSH, l2 and
//                   the solve methods that relight (bi-polynomial, auto)
//   import_rti      a folder of photographs plus an .lp file -> a stack folder

#include "lightstage/host/io/raw_image.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace lightstage::pipeline {

struct ExportSettings {
  std::filesystem::path input;  // a stack folder, or a solve folder (its summary.json names the stack)
  std::filesystem::path out;    // the file (ptm, hsh) or folder (relight) to write; must not exist
  std::string format = "ptm";   // ptm | hsh | relight
  std::string colour;           // ptm, relight: lrgb | rgb; empty = lrgb for ptm, rgb for relight
  int hsh_order = 3;            // hsh, relight --model hsh: 2 (4 terms) | 3 (9 terms)
  std::string model = "ptm";    // relight only: the basis, ptm | hsh
  std::string planes = "jpg";   // relight only: plane images, jpg | png (lossless)
  int quality = 95;             // relight jpg planes: JPEG quality
};

// The stack folder an export reads: `input` itself when it holds a stack,
// else the stack a solve folder's summary.json records as its "input" (then
// `solve_summary`, when given, receives that summary.json). Throws InputError
// naming the folder, summary.json or the recorded input.
std::filesystem::path export_stack_folder(const std::filesystem::path& input,
                                          nlohmann::json* solve_summary = nullptr);

// Fits the stack per pixel and colour channel and writes the file; returns a
// summary (stack, format, size, terms, bytes written). Throws InputError
// naming the flag, the stack file or the existing output.
nlohmann::json export_rti(const ExportSettings& settings);

struct HoldoutSettings {
  std::filesystem::path input;  // a stack folder
  int held_out = 12;            // lights held out one at a time, evenly spaced in the stack's order
  // Solve methods (solve_methods.hpp names) relit as `solve --method M` then
  // `relight` would: solved on the other lights with default settings, the
  // solve folder written and read back, relight.hpp at the held-out light.
  // Empty entries and "none" are skipped; "l2" is the RTI table's own l2.
  std::vector<std::string> methods = {"biquadratic", "auto"};
  int threads = 0;  // solver threads, 0 = all
};

// For each model (ptm, hsh2, hsh3, l2, then `methods`): fit on all lights but
// one, relight at that one, and compare with its photo on the object (mask)
// pixels, using radiometry.hpp's grey values: relative RMSE = ‖relit − photo‖
// / ‖photo‖, then the mean over the held-out lights. Pixels a method did not
// solve count as relit 0. Returns {"held_out": [...indices], "models":
// {"ptm": {"relative_rmse": ..., "per_light": [...]}, ...}, "order": [names]}.
nlohmann::json rti_holdout(const HoldoutSettings& settings);

// The result of rti_holdout as a small text table, one model per line.
std::string format_holdout_table(const nlohmann::json& result);

struct ImportSettings {
  std::filesystem::path input;     // folder of JPEG / PNG / TIFF / camera RAW photographs
  std::filesystem::path lp;        // empty = the one .lp file in `input`
  std::filesystem::path response;  // empty = sRGB curve for 8-bit images; else a `camera response` JSON
  std::filesystem::path out;       // stack folder to create; must be absent or empty
  io::RawDemosaic raw_demosaic = io::RawDemosaic::half;  // for RAW photographs (io/raw_image.hpp)
};

// Reads the .lp, finds each image it names in `input` (by its last path
// component), linearises it (io/rti_import.hpp; RAW files are linear as
// decoded, io/raw_image.hpp) and writes a stack folder (docs/stack-format.md):
// 16-bit PNG frames, light_directions.txt from the .lp, a manifest saying
// where it came from, with each frame's source file, its EXIF (io/exif.hpp;
// the exposure time also as exposure_us) and, for RAW files, the decode.
// Returns the manifest's "import" entry. Throws InputError naming the .lp
// line, the image or --out.
nlohmann::json import_rti(const ImportSettings& settings);

}  // namespace lightstage::pipeline
