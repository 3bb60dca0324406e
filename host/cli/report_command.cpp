// `lightstage report`: the self-contained HTML report of a solve result.
#include "commands.hpp"

#include "lightstage/host/report/report.hpp"

#include <fmt/format.h>

#include <memory>
#include <optional>
#include <string>

namespace lightstage::cli {

void add_report(CLI::App& app) {
  struct Args {
    std::string result;
    std::string out;
    std::string gt;
    std::string calibration;
    std::string stack;
    std::string depth;
    double shadow_threshold = -1;
    bool no_light_statistics = false;
    bool json = false;
    report::ReportOptions options;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "report",
      "Write the HTML report of a solve result (docs/report.md).\n"
      "\n"
      "Input: RESULT_DIR (normal.png, albedo, summary.json, residual/confidence, depth.pfm when present), "
      "the input stack named in summary.json and a calibration.json when one is found.\n"
      "Output: one self-contained HTML page (no network needed to open it; default RESULT_DIR/report.html): "
      "normals with the reference-sphere legend, albedo, depth relief, the lights on the hemisphere "
      "(nominal and calibrated), per-light statistics, residual and confidence maps, the angular error "
      "against ground truth with its histogram, and a relighting viewer (drag the light over a hemisphere; "
      "arrow keys work too). Parts whose inputs are missing are left out with a note. `solve` and `demo` "
      "write RESULT_DIR/report.html themselves.\n"
      "\n"
      "Example: lightstage report out/demo/result --out out/demo/report.html");
  sub->add_option("RESULT_DIR", args->result, "solve output folder")->required();
  sub->add_option("--out", args->out, "the HTML file to write (default RESULT_DIR/report.html)");
  sub->add_option("--gt", args->gt,
                  "ground-truth Normal_gt.png, or a folder holding it (default: the stack's)");
  sub->add_option("--calibration", args->calibration, "calibration.json with nominal and calibrated lights");
  sub->add_option("--depth", args->depth,
                  "depth.pfm, or a `lightstage integrate` output folder (default: RESULT_DIR/depth.pfm)");
  sub->add_option("--stack", args->stack, "the input stack folder (default: summary.json \"input\")");
  sub->add_option("--shadow-threshold", args->shadow_threshold,
                  "value at or below which a pixel counts as shadow in the per-light statistics "
                  "(default: the solver's, else 0.02)");
  sub->add_flag("--no-light-statistics", args->no_light_statistics,
                "do not read the stack's images for per-light statistics");
  sub->add_option("--viewer-max-pixels", args->options.viewer_max_pixels,
                  "largest image the viewer embeds; larger results are subsampled")
      ->capture_default_str();
  sub->add_option("--pyramids", args->options.pyramids,
                  "Deep Zoom pyramids (.dzi and tiles) of the normals and albedo at full size in OUT_files/ "
                  "beside the page: auto (when the result is larger than the page's pictures, 2^21 pixels), "
                  "always or never")
      ->check(CLI::IsMember({"auto", "always", "never"}))
      ->capture_default_str();
  sub->add_option("--pyramid-format", args->options.pyramid_format,
                  "the pyramids' tiles: png (lossless, transparent background) or jpg (smaller, over black)")
      ->check(CLI::IsMember({"png", "jpg"}))
      ->capture_default_str();
  sub->add_flag("--json", args->json, "print what was written as JSON");
  sub->callback([args] {
    report::ReportOptions options = args->options;
    if (!args->gt.empty()) options.ground_truth = args->gt;
    if (!args->calibration.empty()) options.calibration = args->calibration;
    if (!args->stack.empty()) options.stack = args->stack;
    if (!args->depth.empty()) options.depth = args->depth;
    if (args->shadow_threshold >= 0) options.shadow_threshold = args->shadow_threshold;
    options.light_statistics = !args->no_light_statistics;
    const auto summary = report::write_report(args->result, args->out, options);
    if (args->json) {
      fmt::print("{}\n", summary.to_json().dump());
      return;
    }
    fmt::print("wrote {} ({:.1f} MB, {} sections)\n", summary.file.string(),
               static_cast<double>(summary.bytes) / 1e6, summary.sections.size());
    for (const auto& pyramid : summary.pyramids) fmt::print("  pyramid: {}\n", pyramid.string());
    for (const auto& note : summary.notes) fmt::print("  note: {}\n", note);
  });
}

}  // namespace lightstage::cli
