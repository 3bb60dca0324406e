#include "lightstage/pipeline/batch_solve.hpp"

#include "json_file.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/io/output_folder.hpp"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <system_error>

namespace lightstage::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

bool is_stack(const fs::path& folder) {
  std::error_code error;
  return fs::is_regular_file(folder / "filenames.txt", error);
}

std::string same_path_text(const fs::path& path) {
  std::error_code error;
  const fs::path canonical = fs::weakly_canonical(path, error);
  return (error ? path : canonical).lexically_normal().string();
}

// Whether `result` holds a complete solve of `stack` with `method`: its
// summary.json says so and the report, written last, is newer.
bool finished(const fs::path& result, const fs::path& stack, const std::string& method, json& summary) {
  std::error_code error;
  const fs::path summary_file = result / "summary.json", report = result / "report.html";
  if (!fs::is_regular_file(summary_file, error) || !fs::is_regular_file(report, error)) return false;
  if (fs::last_write_time(report, error) < fs::last_write_time(summary_file, error) || error) return false;
  std::ifstream stream(summary_file);
  json j = json::parse(stream, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object() || j.value("method", std::string{}) != method ||
      same_path_text(j.value("input", std::string{})) != same_path_text(stack))
    return false;
  summary = std::move(j);
  return true;
}

}  // namespace

std::vector<BatchCapture> find_batch_captures(const fs::path& folder) {
  std::error_code error;
  if (!fs::is_directory(folder, error)) fail("{}: not a folder of captures", folder.string());
  std::vector<BatchCapture> captures;
  for (const auto& entry : fs::directory_iterator(folder, error)) {
    if (!entry.is_directory()) continue;
    const std::string name = entry.path().filename().string();
    if (is_stack(entry.path()))
      captures.push_back({name, entry.path()});
    else if (is_stack(entry.path() / "stack"))
      captures.push_back({name, entry.path() / "stack"});
  }
  if (error) fail("{}: cannot list it: {}", folder.string(), error.message());
  if (captures.empty())
    fail("{}: no capture in it (a capture is a folder holding filenames.txt, or a stack/ folder that does)",
         folder.string());
  std::sort(captures.begin(), captures.end(),
            [](const BatchCapture& a, const BatchCapture& b) { return a.name < b.name; });
  return captures;
}

json BatchReport::to_json() const {
  json list = json::array();
  for (const BatchOutcome& c : captures) {
    json entry = {{"name", c.name}, {"status", c.status}, {"seconds", c.seconds}};
    if (!c.error.empty()) entry["error"] = c.error;
    if (c.summary.is_object()) {
      for (const char* key : {"method", "pixels_in_mask", "pixels_solved", "usable", "error_vs_ground_truth"})
        if (c.summary.contains(key)) entry[key] = c.summary[key];
    }
    list.push_back(entry);
  }
  return {{"captures", list}, {"solved", solved}, {"done_before", done_before}, {"failed", failed}};
}

BatchReport solve_batch(const fs::path& input, const SolveSettings& settings, const fs::path& out,
                        const SolveCalibration& calibration, const BatchProgress& progress) {
  io::require_separate_output(out, {input});
  const ThreadLimit threads(settings.threads.value_or(0));  // decoding, writing and the report too
  const std::vector<BatchCapture> captures = find_batch_captures(input);
  fs::create_directories(out);
  BatchReport report;
  for (std::size_t i = 0; i < captures.size(); ++i) {
    const BatchCapture& capture = captures[i];
    const fs::path result = out / capture.name;
    BatchOutcome outcome;
    outcome.name = capture.name;
    const auto start = std::chrono::steady_clock::now();
    json summary;
    if (finished(result, capture.stack, settings.method, summary)) {
      outcome.status = "done before";
      outcome.summary = std::move(summary);
      ++report.done_before;
    } else {
      try {
        outcome.summary = solve_folder(capture.stack, settings, result, calibration).summary;
        outcome.status = "solved";
        ++report.solved;
      } catch (const std::exception& e) {
        // One capture's bad file, unusable result or exhausted memory does not stop the others.
        outcome.status = "failed";
        outcome.error = e.what();
        ++report.failed;
        logger("host")->error("{}: {}", capture.name, e.what());
      }
    }
    outcome.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    report.captures.push_back(std::move(outcome));
    write_json_file(out / "batch.json", report.to_json(), 2);
    if (progress) progress(report.captures.back(), i, captures.size());
  }
  return report;
}

}  // namespace lightstage::pipeline
