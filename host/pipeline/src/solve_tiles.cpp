#include "lightstage/pipeline/solve_tiles.hpp"

#include "band_solver.hpp"
#include "json_file.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/common/temporary_path.hpp"
#include "lightstage/host/io/output_folder.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/pipeline/memory_budget.hpp"

#include <fmt/format.h>

#include <charconv>
#include <fstream>
#include <map>
#include <regex>
#include <system_error>

namespace lightstage::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kPlanFormat = "lightstage solve tile plan 1";
// 2: l2's confidence takes every positive observation, not those above the threshold.
constexpr const char* kPartFormat = "lightstage solve tile part 2";
// More jobs than this is a typing error, not a cluster.
constexpr int kMaxTiles = 100000;

fs::path tiles_folder(const fs::path& out) { return out / "tiles"; }
fs::path plan_file(const fs::path& out) { return tiles_folder(out) / "plan.json"; }
fs::path part_folder(const fs::path& out, const TileJob& job) {
  return tiles_folder(out) / fmt::format("part-{}-of-{}", job.index, job.count);
}

std::string absolute_text(const fs::path& path) {
  return path.empty() ? std::string{} : fs::absolute(path).lexically_normal().string();
}

// What changes the observations: a plan's threshold holds for the runs of the same key.
json observations_key(const fs::path& input, const SolveSettings& settings,
                      const SolveCalibration& calibration) {
  return {{"input", absolute_text(input)},
          {"crop", settings.crop},
          {"calibration", absolute_text(calibration.file)},
          {"response", absolute_text(calibration.response)},
          {"clamp_to_one", settings.radiometry.clamp_to_one}};
}

// What the parts of one run share beyond that: the method and its lights.
json run_key(const fs::path& input, const SolveSettings& settings, const SolveCalibration& calibration) {
  json key = observations_key(input, settings, calibration);
  key["method"] = settings.method;
  key["distant_lights"] = calibration.distant;
  return key;
}

json read_json_file(const fs::path& path, const char* format) {
  std::ifstream stream(path);
  if (!stream) fail("{}: cannot read it", path.string());
  json j = json::parse(stream, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object() || j.value("format", std::string{}) != format)
    fail("{}: not a '{}' file (written by another version, or damaged): run the step that wrote it again",
         path.string(), format);
  return j;
}

// The differences between two keys, as "field: 'a' here, 'b' there".
std::string key_differences(const json& ours, const json& theirs) {
  std::vector<std::string> differences;
  for (const auto& [field, value] : ours.items()) {
    const json other = theirs.value(field, json());
    if (other != value)
      differences.push_back(fmt::format("{} {} there, {} here", field, other.dump(), value.dump()));
  }
  return fmt::format("{}", fmt::join(differences, "; "));
}

json facts_json(const std::vector<SolveFact>& facts) {
  json list = json::array();
  for (const SolveFact& fact : facts)
    list.push_back({{"key", fact.key}, {"value", fact.value}, {"text", fact.text}});
  return list;
}

std::vector<SolveFact> facts_from(const json& list) {
  std::vector<SolveFact> facts;
  for (const json& fact : list)
    facts.push_back(
        {fact.at("key").get<std::string>(), fact.at("value"), fact.at("text").get<std::string>()});
  return facts;
}

// Maps are stored as float PFMs (8-bit ones converted, exactly) so a part reads back bit for bit.
void write_map(const fs::path& file, const cv::Mat& map) {
  if (map.empty()) return;
  cv::Mat floats = map;
  if (map.depth() == CV_8U) map.convertTo(floats, CV_32F);
  io::write_pfm(file, floats);
}

cv::Mat read_map(const fs::path& file, int type) {
  if (!fs::exists(file)) return {};
  cv::Mat map = io::read_pfm(file);
  if (CV_MAT_CN(type) != map.channels())
    fail("{}: {} channel(s), expected {}", file.string(), map.channels(), CV_MAT_CN(type));
  if (CV_MAT_DEPTH(type) == CV_8U) map.convertTo(map, CV_8U);
  return map;
}

// A tile's result and what the merge needs to know of it, written into a
// temporary folder then renamed over the part (a job run again replaces its own part).
void write_part(const fs::path& folder, const SolveResult& result, const json& info) {
  const fs::path temporary = temporary_sibling(folder);
  fs::create_directories(temporary);
  write_map(temporary / "normals.pfm", result.normals);
  write_map(temporary / "albedo.pfm", result.albedo);
  write_map(temporary / "residual.pfm", result.residual);
  write_map(temporary / "solved.pfm", result.solved);
  write_map(temporary / "confidence.pfm", result.confidence);
  write_map(temporary / "chroma.pfm", result.chroma);
  write_map(temporary / "choice.pfm", result.choice);
  std::vector<cv::Mat> coefficients;
  if (!result.coefficients.empty()) cv::split(result.coefficients, coefficients);
  for (std::size_t k = 0; k < coefficients.size(); ++k)
    write_map(temporary / fmt::format("coefficient_{}.pfm", k), coefficients[k]);
  json j = info;
  j["format"] = kPartFormat;
  j["method"] = result.summary.method;
  j["parameters"] = result.parameters;
  j["reflectance"] = result.reflectance;
  j["choices"] = result.choices;
  j["coefficients"] = coefficients.size();
  j["counts"] = {
      {"pixels_in_mask", result.summary.pixels_in_mask},
      {"pixels_solved", result.summary.pixels_solved},
      {"pixels_rejected_too_few_observations", result.summary.pixels_rejected_too_few_observations},
      {"pixels_rejected_degenerate", result.summary.pixels_rejected_degenerate}};
  j["seconds"] = result.summary.seconds;
  j["settings"] = facts_json(result.summary.settings);
  j["findings"] = facts_json(result.summary.findings);
  write_json_file(temporary / "part.json", j);
  std::error_code ignored;
  fs::remove_all(folder, ignored);
  fs::rename(temporary, folder);
}

// part.json, with the fields the merge reads before the maps checked.
json read_part_json(const fs::path& folder) {
  const fs::path file = folder / "part.json";
  json j = read_json_file(file, kPartFormat);
  try {
    const json& tile = j.at("tile");
    for (const char* key : {"index", "count", "first_row", "rows"})
      static_cast<void>(tile.at(key).get<int>());
    if (j.at("width").get<int>() <= 0 || j.at("height").get<int>() <= 0 || !j.at("describe").is_object() ||
        !j.at("shadow_threshold").is_object() || !j.at("key").is_object())
      fail("{}: width, height, describe, shadow_threshold or key malformed: run its tile again",
           file.string());
  } catch (const json::exception& e) {
    fail("{}: {}: run its tile again", file.string(), e.what());
  }
  return j;
}

SolveResult read_part(const fs::path& folder, const json& j) {
  SolveResult result;
  try {
    result.normals = read_map(folder / "normals.pfm", CV_32FC3);
    result.albedo = read_map(folder / "albedo.pfm", CV_32FC1);
    result.residual = read_map(folder / "residual.pfm", CV_32FC1);
    result.solved = read_map(folder / "solved.pfm", CV_8UC1);
    result.confidence = read_map(folder / "confidence.pfm", CV_32FC1);
    result.chroma = read_map(folder / "chroma.pfm", CV_32FC3);
    result.choice = read_map(folder / "choice.pfm", CV_8UC1);
    std::vector<cv::Mat> coefficients;
    for (std::size_t k = 0; k < j.at("coefficients").get<std::size_t>(); ++k)
      coefficients.push_back(read_map(folder / fmt::format("coefficient_{}.pfm", k), CV_32FC1));
    if (!coefficients.empty()) cv::merge(coefficients, result.coefficients);
    result.parameters = j.at("parameters");
    result.reflectance = j.at("reflectance");
    result.choices = j.at("choices").get<std::vector<std::string>>();
    SolveSummary& s = result.summary;
    s.method = j.at("method").get<std::string>();
    const json& counts = j.at("counts");
    s.pixels_in_mask = counts.at("pixels_in_mask").get<std::size_t>();
    s.pixels_solved = counts.at("pixels_solved").get<std::size_t>();
    s.pixels_rejected_too_few_observations =
        counts.at("pixels_rejected_too_few_observations").get<std::size_t>();
    s.pixels_rejected_degenerate = counts.at("pixels_rejected_degenerate").get<std::size_t>();
    s.seconds = j.at("seconds").get<double>();
    s.settings = facts_from(j.at("settings"));
    s.findings = facts_from(j.at("findings"));
  } catch (const json::exception& e) {
    fail("{}: part.json: {}", folder.string(), e.what());
  }
  const int rows = j.at("tile").at("rows").get<int>();
  for (const cv::Mat* map : {&result.normals, &result.albedo, &result.residual, &result.solved})
    if (map->empty() || map->rows != rows || map->cols != j.at("width").get<int>())
      fail("{}: a map is missing or not {}x{}: run its tile again", folder.string(), j.at("width").get<int>(),
           rows);
  return result;
}

// The threshold the jobs share: the plan's when `--tile prepare` wrote one for
// these observations, else estimated here (and written as the plan when there is none yet).
ShadowThreshold shared_shadow_threshold(bands::BandSolver& solver, const fs::path& out, const json& key) {
  if (!solver.estimates_shadow_threshold()) return solver.shadow_threshold();
  const fs::path plan = plan_file(out);
  if (fs::exists(plan)) {
    const json j = read_json_file(plan, kPlanFormat);
    if (j.value("key", json()) != key)
      fail("{}: made for another run ({}): remove it, or use another --out", plan.string(),
           key_differences(key, j.value("key", json::object())));
    try {
      return ShadowThreshold::from_json(j.value("shadow_threshold", json::object()));
    } catch (const Error& e) {
      fail("{}: {}: run --tile prepare again", plan.string(), e.what());
    }
  }
  logger("host")->info(
      "{}: no tile plan: estimating the shadow threshold from the whole stack (run --tile "
      "prepare once before the jobs to spare each of them this pass)",
      out.string());
  const ShadowThreshold threshold = solver.shadow_threshold();
  if (!fs::exists(plan))
    write_json_file(plan, {{"format", kPlanFormat}, {"key", key}, {"shadow_threshold", threshold.to_json()}});
  return threshold;
}

BandPlan plan_for(const fs::path& input, const SolveSettings& settings) {
  io::StackOutline outline = io::read_stack_outline(input);
  outline.size.height = solve_region(settings, outline.size, input).height;
  return plan_bands(outline, parse_memory_limit(settings.memory_limit));
}

SolveReport prepare_tiles(const fs::path& input, const SolveSettings& settings, const fs::path& out,
                          const SolveCalibration& calibration) {
  io::StackBands stack(input);
  bands::BandSolver solver(input, settings, calibration, stack, plan_for(input, settings));
  fs::create_directories(tiles_folder(out));
  const json key = observations_key(input, settings, calibration);
  const ShadowThreshold threshold = solver.shadow_threshold();
  write_json_file(plan_file(out),
                  {{"format", kPlanFormat}, {"key", key}, {"shadow_threshold", threshold.to_json()}});
  SolveReport report;
  report.summary = {{"tile", "prepare"},
                    {"plan", plan_file(out).string()},
                    {"parameters", {{"shadow_threshold_choice", threshold.to_json()}}}};
  return report;
}

SolveReport solve_one_tile(const fs::path& input, const SolveSettings& settings, const fs::path& out,
                           const SolveCalibration& calibration, const TileJob& job,
                           const ProgressStart& progress) {
  io::StackBands stack(input);
  bands::BandSolver solver(input, settings, calibration, stack, plan_for(input, settings));
  const int height = solver.size().height;
  if (job.count > height)
    fail("--tile {}/{}: more tiles than the image has rows ({})", job.index, job.count, height);
  const auto [first, end] = tile_rows(job, height);
  if (progress) solver.set_progress(progress(solve_work(settings, solver.mask_pixels(first, end))));
  fs::create_directories(tiles_folder(out));
  const ShadowThreshold threshold =
      shared_shadow_threshold(solver, out, observations_key(input, settings, calibration));
  AngularErrorAccumulator unused;
  bool ground_truth = false;
  // A tile's maps are held (its rows only) and written as its part.
  bands::BandResults maps({solver.size().width, end - first}, /*keep_maps=*/true);
  int row = 0;
  solver.solve_rows(first, end, threshold, unused, ground_truth, [&](const SolveResult& band, int rows) {
    if (!band.normals.empty()) maps.add(band, row);
    row += rows;
  });
  const SolveResult result = maps.finish();
  json info = {
      {"key", run_key(input, settings, calibration)},
      {"tile", {{"index", job.index}, {"count", job.count}, {"first_row", first}, {"rows", end - first}}},
      {"width", solver.size().width},
      {"height", height},
      {"shadow_threshold", threshold.to_json()},
      {"ground_truth", ground_truth},
      {"describe", solver.describe()}};
  if (solver.light_statistics()) info["light_statistics"] = solver.light_statistics()->to_json();
  const fs::path folder = part_folder(out, job);
  write_part(folder, result, info);
  logger("host")->info("tile {}/{} (rows {}-{}): {}", job.index, job.count, first, end - 1,
                       result.summary.message);
  SolveReport report;
  report.summary = result.summary.to_json();
  report.summary["method"] = settings.method;
  report.summary["tile"] = info["tile"];
  report.summary["part"] = folder.string();
  return report;
}

// The parts in OUT/tiles by index, all of one count; throws naming what is missing.
std::vector<fs::path> find_parts(const fs::path& out) {
  const fs::path folder = tiles_folder(out);
  std::map<int, fs::path> parts;
  std::optional<int> count;
  const std::regex name(R"(part-(\d+)-of-(\d+))");
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(folder, error)) {
    std::smatch m;
    const std::string file = entry.path().filename().string();
    if (!entry.is_directory() || !std::regex_match(file, m, name)) continue;
    const TileJob job = parse_tile_job(m[1].str() + "/" + m[2].str());
    if (count && *count != job.count)
      fail("{}: parts of {} and of {} tiles: remove the parts of the other run", folder.string(), *count,
           job.count);
    count = job.count;
    parts[job.index] = entry.path();
  }
  if (!count) fail("{}: no tile parts to merge: run the --tile I/N jobs first", folder.string());
  std::vector<std::string> missing;
  for (int i = 0; i < *count; ++i)
    if (parts.count(i) == 0) missing.push_back(std::to_string(i));
  if (!missing.empty())
    fail("{}: tile(s) {} of {} missing: run --tile I/{} for each", folder.string(), fmt::join(missing, ", "),
         *count, *count);
  std::vector<fs::path> ordered;
  for (auto& [index, path] : parts) ordered.push_back(path);
  return ordered;
}

SolveReport merge_tiles(const fs::path& input, const SolveSettings& settings, const fs::path& out,
                        const SolveCalibration& calibration) {
  const std::vector<fs::path> parts = find_parts(out);
  const json key = run_key(input, settings, calibration);
  std::optional<bands::BandResults> results;
  std::optional<io::SolveOutputWriter> writer;
  std::optional<report::LightStatisticsTally> light_statistics;
  bool statistics_complete = true;
  json first;
  // The ground truth the jobs saw, read again here without the frames, and the error part by part.
  std::optional<ImageStack> truth;
  cv::Rect region;
  AngularErrorAccumulator error;
  int next_row = 0;
  for (const fs::path& part : parts) {
    const json j = read_part_json(part);
    if (j.value("key", json()) != key)
      fail("{}: solved by another run ({})", part.string(),
           key_differences(key, j.value("key", json::object())));
    if (first.is_null()) {
      first = j;
      const cv::Size size(j.at("width").get<int>(), j.at("height").get<int>());
      results.emplace(size, /*keep_maps=*/false);
      writer.emplace(out, size);
    } else if (j.value("shadow_threshold", json()) != first["shadow_threshold"]) {
      fail(
          "{}: solved with another shadow threshold than {} ({} against {}): run --tile prepare, then every "
          "tile again",
          part.string(), parts.front().string(), j.value("shadow_threshold", json()).dump(),
          first["shadow_threshold"].dump());
    } else if (j.value("width", 0) != first["width"] || j.value("height", 0) != first["height"]) {
      fail("{}: an image of another size than {}", part.string(), parts.front().string());
    }
    const SolveResult result = read_part(part, j);
    if (const auto it = j.find("light_statistics"); it != j.end() && statistics_complete) {
      const auto tally = report::LightStatisticsTally::from_json(*it, (part / "part.json").string());
      if (light_statistics)
        light_statistics->add(tally);
      else
        light_statistics = tally;
    } else if (result.summary.pixels_in_mask > 0) {
      statistics_complete = false;  // a part without them: none rather than some of the pixels' statistics
      light_statistics.reset();
    }
    // A tile without a mask pixel holds zeros only, and no method facts.
    const int first_row = j.at("tile").at("first_row").get<int>(), rows = j.at("tile").at("rows").get<int>();
    if (first_row != next_row)
      fail("{}: rows {} to {}, where the parts before end at row {}: run its tile again", part.string(),
           first_row, first_row + rows - 1, next_row);
    next_row += rows;
    if (result.summary.pixels_in_mask == 0) {
      writer->add_empty(rows);
      continue;
    }
    results->add(result, first_row);
    writer->add(result);
    if (!j.value("ground_truth", false)) continue;
    if (!truth) {
      io::LoadOptions options;
      options.frame_pixels = false;
      truth = io::load_stack(input, options);
      if (!truth->ground_truth || truth->ground_truth->normals.empty())
        fail("{}: the tile jobs read ground truth that is gone", input.string());
      region = solve_region(settings, truth->ground_truth->normals.size(), input);
    }
    const cv::Rect rows_of_part(region.x, region.y + first_row, region.width, rows);
    error.add(result.normals, truth->ground_truth->normals(rows_of_part),
              truth->mask.empty() ? cv::Mat() : truth->mask(rows_of_part));
  }
  const SolveResult result = results->finish();
  json extra = first.at("describe");
  extra["bands"]["tiles"] = parts.size();
  if (light_statistics) extra["light_statistics"] = light_statistics->summary_json();
  SolveReport report = bands::write_band_solve(input, out, *writer, result, extra,
                                               truth ? std::optional(error.stats()) : std::nullopt);
  fs::remove_all(tiles_folder(out));
  return report;
}

}  // namespace

TileJob parse_tile_job(const std::string& text) {
  const auto slash = text.find('/');
  TileJob job;
  const auto number = [&](std::string_view part, int& value) {
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), value);
    return ec == std::errc{} && end == part.data() + part.size() && !part.empty();
  };
  if (slash == std::string::npos || !number(std::string_view(text).substr(0, slash), job.index) ||
      !number(std::string_view(text).substr(slash + 1), job.count))
    fail("--tile '{}': expected I/N (this job's tile of N, from 0), prepare or merge", text);
  if (job.count < 1 || job.count > kMaxTiles) fail("--tile '{}': N must be 1 to {}", text, kMaxTiles);
  if (job.index < 0 || job.index >= job.count)
    fail("--tile '{}': I must be 0 to {} (tiles count from 0)", text, job.count - 1);
  return job;
}

std::pair<int, int> tile_rows(const TileJob& job, int height) {
  const auto row = [&](int index) {
    return static_cast<int>(static_cast<long long>(height) * index / job.count);
  };
  return {row(job.index), row(job.index + 1)};
}

SolveReport solve_tile(const fs::path& input, const SolveSettings& settings, const fs::path& out,
                       const SolveCalibration& calibration, const std::string& tile,
                       const ProgressStart& progress) {
  io::require_separate_output(out, {input});
  const ThreadLimit threads(settings.threads.value_or(0));  // decoding, writing and the report too
  if (!solves_in_tiles(settings))
    fail(
        "--tile: --method {} needs the whole image at once; tiles solve {} (and no --azimuth-from a "
        "bi-polynomial method)",
        settings.method, tile_methods_text());
  if (tile == "prepare") return prepare_tiles(input, settings, out, calibration);
  if (tile == "merge") return merge_tiles(input, settings, out, calibration);
  return solve_one_tile(input, settings, out, calibration, parse_tile_job(tile), progress);
}

}  // namespace lightstage::pipeline
