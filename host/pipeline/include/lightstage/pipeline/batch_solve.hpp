#pragma once
// `lightstage batch`: every capture in a folder solved with the same flags,
// one after the other, into a result folder each, with one summary. A batch
// run again carries on where it stopped: a capture whose result is complete
// (summary.json of the same input and method, and the report written after
// it) is skipped; one that failed or was interrupted is solved again. A
// capture that fails is recorded with its error and the batch goes on.

#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/pipeline/solve_settings.hpp"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace lightstage::pipeline {

// A capture of the batch: a stack folder (holding filenames.txt) directly in
// the batch's folder, or its `stack` subfolder (what `demo` and `capture`
// write), named by the folder under the batch's.
struct BatchCapture {
  std::string name;
  std::filesystem::path stack;
};

// The captures in `folder`, by name. Throws InputError naming the folder
// when it is missing or holds none.
std::vector<BatchCapture> find_batch_captures(const std::filesystem::path& folder);

struct BatchOutcome {
  std::string name;
  std::string status;                // "solved", "done before" or "failed"
  std::string error;                 // why it failed
  nlohmann::json summary = nullptr;  // summary.json of the result (solved or done before)
  double seconds = 0;
};

struct BatchReport {
  std::vector<BatchOutcome> captures;
  std::size_t solved = 0, done_before = 0, failed = 0;
  nlohmann::json to_json() const;
};

// Called after each capture, for the CLI's progress lines.
using BatchProgress = std::function<void(const BatchOutcome& outcome, std::size_t index, std::size_t total)>;

// Solves every capture of `input` into `out`/NAME and writes `out`/batch.json
// (after each capture, so an interrupted batch leaves what it had done).
// Throws InputError, before solving anything, for an `out` inside `input`, a
// bad setting or no capture.
BatchReport solve_batch(const std::filesystem::path& input, const SolveSettings& settings,
                        const std::filesystem::path& out, const SolveCalibration& calibration,
                        const BatchProgress& progress = {});

}  // namespace lightstage::pipeline
