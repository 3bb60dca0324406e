#pragma once
// Solving a stack larger than memory band by band: row bands of every frame
// decoded together (io/stack_bands.hpp), made into observations, solved and
// pasted into the whole image's maps, so that the stack itself is never held.
// The result equals solving the whole image at once (the same normals,
// albedo, residual, confidence and chroma, float for float):
//   pass 1  the shadow threshold's samples (shadow_threshold.hpp), drawn from
//           the whole image's pixels as a whole-image solve draws them (not
//           with --shadow-threshold: the stack is then decoded once);
//   pass 2  each band solved with that threshold; a pixel's place in the whole
//           image (Observations::origin, first_pixel) gives its near lights
//           and its random seed.
// The per-pixel methods without a whole-object step are solved so: l2,
// robust, monotonic, l1 and sbl. The bi-polynomial methods and auto refit
// their relighting model over the whole object, rpca decomposes blocks of
// pixels and shape-prior smooths across them: they are refused in bands.
// The output maps are held whole (about 50 bytes a pixel).

#include "lightstage/host/io/stack_bands.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/pipeline/solve_settings.hpp"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <filesystem>
#include <string>

namespace lightstage::pipeline {

// What solving a stack costs, estimated from its headers (an upper bound:
// every pixel counted as inside the mask).
struct BandPlan {
  std::size_t whole_bytes = 0;   // the whole image solved at once
  std::size_t fixed_bytes = 0;   // held whatever the band height: the masks, the errors against ground truth
  std::size_t row_bytes = 0;     // per row of a band: decoded images, observations, the band's maps
  std::size_t report_bytes = 0;  // the report after the solve (report::report_memory_bytes)
  std::size_t limit_bytes = 0;   // the --memory-limit planned for
  int band_rows = 0;             // rows per band (the image's height: one band, solved whole)
  int bands = 1;

  nlohmann::json to_json() const;
};

// The plan for solving `stack` within `memory_limit` bytes: the whole image
// when it fits, else the tallest bands that fit. Throws InputError naming
// --memory-limit when not even a band of one row fits.
BandPlan plan_bands(const io::StackOutline& stack, std::size_t memory_limit);

// Whether `method` can be solved band by band (see above).
bool solves_in_bands(const std::string& method);
// Those methods, "l2, robust, ...", for messages.
std::string band_methods_text();

// Solves `stack` (opened from `input`) in the bands of `plan` and writes the
// solve folder as solve_folder does. Throws InputError, before reading any
// pixel, for a method that cannot be solved in bands (naming the memory it
// needs whole and --memory-limit).
SolveReport solve_folder_in_bands(const std::filesystem::path& input, const SolveSettings& settings,
                                  const std::filesystem::path& out, const SolveCalibration& calibration,
                                  io::StackBands& stack, const BandPlan& plan);

}  // namespace lightstage::pipeline
