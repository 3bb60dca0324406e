#pragma once
// Solving a stack larger than memory band by band: row bands of every frame
// decoded together (io/stack_bands.hpp), made into observations, solved and
// written to the solve folder band by band (io/solve_output_writer.hpp), so
// that neither the stack nor the result is ever held whole. The result equals
// solving the whole image at once (the same maps float for float, the same
// counts and facts). What the whole-image solve estimates from the whole
// object, each in a pass over every band first:
//   the shadow threshold's samples (shadow_threshold.hpp), drawn from the
//     whole image's pixels as a whole-image solve draws them (not with
//     --shadow-threshold; l2 dropping no shadows only records the
//     threshold, so its samples are gathered from the bands it solves and
//     the stack is read once);
//   the incidence fall-off κ of the bi-polynomial methods and auto
//     (incidence_falloff.hpp; not with --falloff);
// then each band is solved, the next band decoded beside it where the memory
// limit holds two bands' frames (BandPlan::read_ahead); a pixel's place in the whole image
// (Observations::origin, first_pixel) gives its near lights and its random
// seed. The bi-polynomial methods and auto refit their coefficients for
// relighting over the whole object (reflectance/relighting_fit.hpp): their
// solved bands wait in a spill file in the output folder (about 80 bytes a
// pixel) while a sample of every band fits the object's model, then each band
// is refitted and written (two more passes). rpca decomposes blocks cut from
// runs of whole rows, which its bands keep whole; shape-prior smooths across
// the image and is refused in bands.

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
  std::size_t whole_bytes = 0;  // the whole image solved at once
  std::size_t fixed_bytes = 0;  // held whatever the band height: the masks, the errors against ground truth
  std::size_t row_bytes = 0;    // per row of a band: decoded images, observations, the band's maps
  // Per row of a band, beside row_bytes, to decode the next band's images while one is solved.
  std::size_t read_ahead_row_bytes = 0;
  std::size_t report_bytes = 0;  // the report after the solve (report::report_memory_bytes)
  std::size_t limit_bytes = 0;   // the --memory-limit planned for
  int band_rows = 0;             // rows per band (the image's height: one band, solved whole)
  int bands = 1;
  // The next band is read while one is solved: in bands, where a band of a row and the next one's row fit.
  bool read_ahead = false;

  nlohmann::json to_json() const;
};

// The plan for solving `stack` within `memory_limit` bytes: the whole image
// when it fits, else the tallest bands that fit. Throws InputError naming
// --memory-limit when not even a band of one row fits.
// `coefficient_terms`: the most reflectance coefficients a pixel of the
// method's result has (coefficient_terms in solve_methods.hpp);
// `working_bytes`: what the solver holds beside its band whatever the band's
// height (solver_working_bytes).
BandPlan plan_bands(const io::StackOutline& stack, std::size_t memory_limit, int coefficient_terms = 0,
                    std::size_t working_bytes = 0);

// Whether `method` can be solved band by band (see above).
bool solves_in_bands(const std::string& method);
// Those methods, "l2, robust, ...", for messages.
std::string band_methods_text();
// Whether `settings` can be solved as tiles by independent jobs (solve_tiles.hpp): the band methods
// without an object-wide estimate but the threshold.
bool solves_in_tiles(const SolveSettings& settings);
std::string tile_methods_text();

// Solves `stack` (opened from `input`) in the bands of `plan` and writes the
// solve folder as solve_folder does. Throws InputError, before reading any
// pixel, for a method that cannot be solved in bands (naming the memory it
// needs whole and --memory-limit).
SolveReport solve_folder_in_bands(const std::filesystem::path& input, const SolveSettings& settings,
                                  const std::filesystem::path& out, const SolveCalibration& calibration,
                                  io::StackBands& stack, const BandPlan& plan);

}  // namespace lightstage::pipeline
