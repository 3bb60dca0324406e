#pragma once
// One capture solved by many jobs (`solve --tile`): the image's rows split
// into N tiles, each solved by an independent job (a Slurm array task, a GNU
// parallel slot) into a part, then the parts merged into the solve folder a
// single run writes — the same maps float for float, the same counts, facts
// and error (docs/large-captures.md).
//   --tile prepare  estimates the shadow threshold from the whole stack once
//                   and writes it to OUT/tiles/plan.json for the jobs to share
//                   (without it each job estimates it itself: the same value,
//                   one more pass over the whole stack per job);
//   --tile I/N      solves rows [I·H/N, (I+1)·H/N) into OUT/tiles/part-I-of-N/,
//                   in bands under --memory-limit; a job run again replaces
//                   its own part;
//   --tile merge    checks that every part of one run is there and agrees,
//                   writes the solve folder and its report into OUT, then
//                   removes OUT/tiles.
// The methods are those that solve in bands (solve_bands.hpp).

#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/pipeline/solve_settings.hpp"

#include <filesystem>
#include <string>
#include <utility>

namespace lightstage::pipeline {

struct TileJob {
  int index = 0;
  int count = 1;
};

// "I/N" with 0 <= I < N; throws InputError naming --tile.
TileJob parse_tile_job(const std::string& text);

// Rows [first, second) of tile `job` in an image `height` rows tall: the
// rows split as evenly as they go.
std::pair<int, int> tile_rows(const TileJob& job, int height);

// Runs `--tile TEXT` ("prepare", "I/N" or "merge"). The report's summary is
// summary.json for merge; for the others what the job wrote (its part's
// counts, or the plan), with "tile" saying which. Throws InputError naming
// the file, part or flag at fault: a method that does not solve in bands, a
// plan or part of another input or run, a missing part, more tiles than rows.
SolveReport solve_tile(const std::filesystem::path& input, const SolveSettings& settings,
                       const std::filesystem::path& out, const SolveCalibration& calibration,
                       const std::string& tile, const ProgressStart& progress = {});

}  // namespace lightstage::pipeline
