#pragma once
// The report of a solve: one self-contained HTML page (docs/report.md) that a
// person opens offline to judge a capture — normals with the reference-sphere
// legend, albedo, depth relief, the lights on the hemisphere (nominal and
// calibrated), per-light statistics, the residual / confidence maps, the
// angular error against ground truth, and a relighting viewer. Every image is
// an embedded PNG data URI, every plot SVG written here, the viewer's
// JavaScript is compiled into the program (host/src/report/web/).
//
// Inputs, all found from the result folder:
//   RESULT_DIR/normal.png, albedo.pfm|albedo.png, summary.json   (required: normal.png)
//   RESULT_DIR/residual.pfm, confidence.pfm, depth.pfm           (each optional)
//   ReportOptions::depth: a `lightstage integrate` folder (depth.pfm, surface.json)
//   the input stack, summary.json "input" (or ReportOptions::stack): light
//     directions, per-light statistics, mask, Normal_gt.png
//   calibration.json: ReportOptions::calibration, RESULT_DIR/calibration.json,
//     summary.json "calibration", or the stack manifest's "calibration"
// A part whose input is missing is left out with a note saying why.

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::report {

struct ReportOptions {
  // Ground-truth normals: a Normal_gt.png (project encoding) or a folder
  // holding one (and optionally mask.png). Default: the input stack's.
  std::optional<std::filesystem::path> ground_truth;
  // A calibration.json (nominal and calibrated light positions). Default: found as above.
  std::optional<std::filesystem::path> calibration;
  // Depth: a depth.pfm, or a `lightstage integrate` output folder holding one
  // (its surface.json gives the camera). Default: RESULT_DIR/depth.pfm.
  std::optional<std::filesystem::path> depth;
  // The input stack folder. Default: summary.json "input".
  std::optional<std::filesystem::path> stack;
  // Per-light statistics need the stack's images; off skips loading them.
  bool light_statistics = true;
  // Shadow threshold for the per-light shadow share; unset = the solver's
  // (summary.json parameters.shadow_threshold when > 0), else 0.02.
  std::optional<double> shadow_threshold;
  // The viewer embeds at most this many pixels (larger results are subsampled).
  int viewer_max_pixels = 1 << 20;
  // Each picture embeds at most this many pixels (larger results are shown
  // averaged over blocks of pixels).
  int picture_max_pixels = 1 << 21;
  // The result's maps are read this many rows at a time; 0 = as many as fit a
  // few tens of megabytes (result_maps.hpp), so that a result larger than
  // memory is reported from its files.
  int band_rows = 0;
  // With band_rows 0, maps that fit in this many bytes are read once and
  // kept for the report's three passes instead of decoded for each; 0 = read
  // a band at a time always (a solve under --memory-limit).
  std::size_t kept_map_bytes = std::size_t{128} << 20;
  // The page's sections (their pictures, the viewer's payload) are made side
  // by side on this many threads (0 = every core); 1 holds one at a time.
  int threads = 0;
  // Deep Zoom pyramids of the normal and albedo pictures at the result's full
  // size, beside the page in PAGE_files/ (deep_zoom.hpp): "auto" when the
  // result is larger than picture_max_pixels (the page's pictures are then
  // overviews), "always" or "never"; their tiles' format (png or jpg).
  std::string pyramids = "auto";
  std::string pyramid_format = "png";

  void check() const;  // throws InputError naming the field and value
};

struct ReportSummary {
  std::filesystem::path file;                   // the page written
  std::size_t bytes = 0;                        // its size
  std::vector<std::string> sections;            // ids of the sections present, in page order
  std::vector<std::string> notes;               // what was left out or approximated, and why
  std::vector<std::filesystem::path> pyramids;  // the Deep Zoom descriptors written (.dzi)

  nlohmann::json to_json() const;
};

// An upper bound of the memory write_report takes (beside the program) for a
// result of `width` × `height` pixels: what it holds for the whole image (the
// solved, ground-truth and compared masks, the compared pixels' errors), two bands of rows,
// the pictures and viewer data at their page budgets, and the page itself.
std::size_t report_memory_bytes(int width, int height, const ReportOptions& options = {});

// Builds the page for `result_dir`. `summary`, when given, receives the same
// information write_report returns (without file and bytes). When the page
// will be `page_file` (PAGE.html), the pyramids options ask for go to
// PAGE_files/ beside it with their zoom page; a PAGE_files/ of an earlier
// report is removed when there are none now, and one a report did not write
// is refused. An empty `page_file` writes no files.
std::string render_report(const std::filesystem::path& result_dir, const ReportOptions& options = {},
                          ReportSummary* summary = nullptr, const std::filesystem::path& page_file = {});

// render_report, written atomically to `out` (default RESULT_DIR/report.html).
// Throws InputError for an `out` that is not a .html file name (so it cannot
// be one of the report's inputs).
ReportSummary write_report(const std::filesystem::path& result_dir, const std::filesystem::path& out = {},
                           const ReportOptions& options = {});

}  // namespace lightstage::report
