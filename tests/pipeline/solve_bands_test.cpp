// A stack solved in bands (solve_bands.hpp) equals the same stack solved whole:
// the same maps float for float, the same counts, threshold and error.
#include "lightstage/pipeline/solve_bands.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/exr.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/pipeline/memory_budget.hpp"
#include "lightstage/pipeline/simulate_folder.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/pipeline/solve_methods.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/light_statistics.hpp"
#include "lightstage/testing/paths.hpp"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>
#include <optional>
#include <string>

namespace lightstage::pipeline {
namespace {

namespace fs = std::filesystem;
using lightstage::testing::error_of;
using ::testing::HasSubstr;

fs::path rig_path() { return lightstage::testing::source_dir() / "hw/rigs/sim-dome.yaml"; }

// A noisy capture of near LEDs (the simulator's default) with a mask.
fs::path simulated(const fs::path& dir, const std::string& scene, const std::string& colour = {}) {
  sim::SimulateOptions o;
  o.scene = scene;
  o.width = 40;
  o.height = 36;
  o.colour = colour;
  simulate_to_folder(rig_path(), o, dir);
  return dir;
}

SolveSettings settings_for(const std::string& method, const std::string& memory_limit) {
  SolveSettings s;
  s.method = method;
  s.threads = 2;
  s.memory_limit = memory_limit;
  s.resolve();
  return s;
}

// A --memory-limit that gives `stack` solved with `settings` bands of `rows` rows.
std::string limit_for_rows(const fs::path& stack, int rows,
                           const SolveSettings& settings = settings_for("l2", "auto")) {
  const io::StackOutline outline = io::read_stack_outline(stack);
  const BandPlan whole =
      plan_bands(outline, std::numeric_limits<std::size_t>::max(), coefficient_terms(settings.method),
                 solver_working_bytes(settings, outline.images));
  return std::to_string(whole.fixed_bytes +
                        static_cast<std::size_t>(rows) * (whole.row_bytes + whole.read_ahead_row_bytes));
}

void expect_same_map(const cv::Mat& a, const cv::Mat& b, const std::string& what) {
  ASSERT_EQ(a.type(), b.type()) << what;
  ASSERT_EQ(a.size(), b.size()) << what;
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0) << what;
}

// Solves `stack` whole and in bands of 5 rows with `settings`, each band in
// parts of 2, 2 and 1 rows, and compares what they wrote. rpca's bands end
// where its runs of rows do: at most 5 rows, `bands` or more of them, each whole.
void expect_bands_equal_whole(const fs::path& stack, SolveSettings settings, const fs::path& out,
                              int bands = 8) {
  const std::string name = settings.method;
  const SolveReport whole = solve_folder(stack, settings, out / (name + "_whole"));
  settings.memory_limit = limit_for_rows(stack, 5, settings);
  const io::StackOutline outline = io::read_stack_outline(stack);
  settings.band_part_bytes =
      2 * static_cast<std::size_t>(outline.size.width) * outline.images * sizeof(float);
  const SolveReport banded = solve_folder(stack, settings, out / (name + "_bands"));
  SCOPED_TRACE(name);
  EXPECT_FALSE(whole.summary.contains("bands"));
  ASSERT_TRUE(banded.summary.contains("bands"));
  if (settings.method == "rpca") {
    EXPECT_LE(banded.summary["bands"]["band_rows"], 5);
    EXPECT_GE(banded.summary["bands"]["bands"], bands);
    EXPECT_EQ(banded.summary["bands"]["part_rows"], banded.summary["bands"]["band_rows"]);
  } else {
    EXPECT_EQ(banded.summary["bands"]["band_rows"], 5);
    EXPECT_EQ(banded.summary["bands"]["bands"], bands);
    EXPECT_EQ(banded.summary["bands"]["part_rows"], 2);
  }
  for (const char* key : {"pixels_in_mask", "pixels_solved", "pixels_rejected_too_few_observations",
                          "pixels_rejected_degenerate", "lights", "radiometry"})
    EXPECT_EQ(banded.summary[key], whole.summary[key]) << key;
  // Every parameter (the threshold chosen, the fall-off estimated), fact and the reflectance with its refit.
  EXPECT_EQ(banded.summary["parameters"], whole.summary["parameters"]);
  EXPECT_EQ(banded.summary["facts"], whole.summary["facts"]);
  EXPECT_EQ(banded.summary.value("reflectance", nlohmann::json()),
            whole.summary.value("reflectance", nlohmann::json()));
  EXPECT_EQ(banded.summary.value("method_map", nlohmann::json()),
            whole.summary.value("method_map", nlohmann::json()));
  EXPECT_EQ(banded.summary["files"], whole.summary["files"]);
  ASSERT_TRUE(whole.error && banded.error);
  EXPECT_EQ(banded.error->mean, whole.error->mean);
  EXPECT_EQ(banded.error->median, whole.error->median);
  EXPECT_EQ(banded.error->count, whole.error->count);
  const fs::path a = out / (name + "_whole"), b = out / (name + "_bands");
  expect_same_map(io::read_exr(b / "normal.exr", {"R", "G", "B"}),
                  io::read_exr(a / "normal.exr", {"R", "G", "B"}), "normals");
  for (const char* file : {"albedo.pfm", "residual.pfm", "confidence.pfm"})
    expect_same_map(io::read_pfm(b / file), io::read_pfm(a / file), file);
  if (fs::exists(a / "albedo_rgb.pfm"))
    expect_same_map(io::read_pfm(b / "albedo_rgb.pfm"), io::read_pfm(a / "albedo_rgb.pfm"), "albedo_rgb.pfm");
  for (const auto& file : whole.summary["files"].value("brdf", nlohmann::json::array())) {
    const std::string brdf = file.get<std::string>();
    expect_same_map(io::read_pfm(b / brdf), io::read_pfm(a / brdf), brdf);
  }
  if (fs::exists(a / "method_map.png"))
    expect_same_map(io::read_image(b / "method_map.png"), io::read_image(a / "method_map.png"),
                    "method_map.png");
  // Nothing left behind but the solve folder's own files (the refit's spill goes).
  for (const auto& entry : fs::directory_iterator(b))
    EXPECT_NE(entry.path().filename().string().front(), '.') << entry.path();
  lightstage::testing::expect_same_light_statistics(whole.summary, banded.summary);
  // The report shows them without decoding the stack again.
  EXPECT_NE(lightstage::testing::read_text(b / "report.html").find("<section id=\"light-statistics\">"),
            std::string::npos);
  EXPECT_TRUE(fs::exists(b / "report.html"));
}

TEST(SolveBands, EveryMethodThatSolvesInBandsGivesTheWholeImageResult) {
  const fs::path dir = lightstage::testing::scratch_dir();
  const fs::path stack = simulated(dir / "stack", "bumps");
  for (const char* method : {"l2", "robust", "monotonic", "l1", "sbl"})
    expect_bands_equal_whole(stack, settings_for(method, "auto"), dir);
}

// l2 drops no shadows and only records the shadow threshold, so its samples
// come from the bands it solves: one pass over the stack. A method that drops
// shadows needs the threshold before its first band: two passes, and one
// again with --shadow-threshold. On a sphere with background around it and
// bands without a mask pixel, the threshold gathered equals the whole image's.
// Dark frames (two exposures' darks, each shared by half the frames) cut
// into parts as the frames are.
TEST(SolveBands, DarkFramesInBandsAndPartsGiveTheWholeImageResult) {
  const fs::path dir = lightstage::testing::scratch_dir();
  ImageStack stack = io::load_stack(simulated(dir / "simulated", "bumps", "0.9,0.6,0.3"));
  const cv::Mat& first = stack.frames.front().image;
  cv::Mat dark_a(first.size(), first.type()), dark_b(first.size(), first.type());
  cv::RNG rng(5);
  rng.fill(dark_a, cv::RNG::UNIFORM, 0, 60);
  rng.fill(dark_b, cv::RNG::UNIFORM, 0, 60);
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    const bool a = i % 2 == 0;
    stack.frames[i].dark = a ? dark_a : dark_b;
    stack.frames[i].dark_file = a ? "dark_a.png" : "dark_b.png";
  }
  io::write_stack(dir / "stack", stack);
  for (const char* method : {"l2", "robust"})
    expect_bands_equal_whole(dir / "stack", settings_for(method, "auto"), dir / method);
}

TEST(SolveBands, L2ReadsTheStackOnceAndAMethodThatDropsShadowsTwice) {
  const fs::path dir = lightstage::testing::scratch_dir();
  const fs::path stack = simulated(dir / "stack", "sphere");
  const io::StackOutline outline = io::read_stack_outline(stack);
  const auto rows = static_cast<std::size_t>(outline.size.height);
  struct Case {
    const char* method;
    std::optional<double> flag;
    std::size_t passes;
  };
  for (const Case& c : {Case{"l2", std::nullopt, 1}, Case{"robust", std::nullopt, 2}, Case{"l2", 0.01, 1},
                        Case{"robust", 0.01, 1}}) {
    const std::string name = fmt::format("{} {}", c.method, c.flag ? "with the flag" : "without the flag");
    SolveSettings settings = settings_for(c.method, "auto");
    settings.shadow_threshold = c.flag;
    settings.resolve();
    const SolveReport whole = solve_folder(stack, settings, dir / (name + " whole"));
    settings.memory_limit = limit_for_rows(stack, 5, settings);
    const BandPlan plan =
        plan_bands(outline, parse_memory_limit(settings.memory_limit), coefficient_terms(settings.method),
                   solver_working_bytes(settings, outline.images));
    ASSERT_EQ(plan.bands, 8);
    io::StackBands bands(stack);
    const SolveReport banded = solve_folder_in_bands(stack, settings, dir / name, {}, bands, plan);
    EXPECT_EQ(bands.rows_read(), c.passes * rows) << name;
    const auto& choice = banded.summary["parameters"]["shadow_threshold_choice"];
    EXPECT_EQ(choice, whole.summary["parameters"]["shadow_threshold_choice"]) << name;
    EXPECT_EQ(choice["source"], c.flag ? "flag" : "noise floor") << name;
    if (!c.flag) {
      EXPECT_GT(choice["object_samples"].get<int>(), 0) << name;
      EXPECT_GT(choice["background_samples"].get<int>(), 0) << name;
    }
    EXPECT_EQ(choice["used_by_l2"], c.flag && std::string(c.method) == "l2") << name;
    // l2 without the flag: its confidence takes every positive observation.
    EXPECT_EQ(banded.summary["parameters"]["confidence"]["shadow_threshold"],
              std::string(c.method) == "l2" && !c.flag ? 0.0 : choice["value"].get<double>())
        << name;
    expect_same_map(io::read_pfm(dir / name / "confidence.pfm"),
                    io::read_pfm(dir / (name + " whole") / "confidence.pfm"), name);
  }
}

// The next band is decoded while one is solved where two bands' frames fit; where a band's row fits but
// not the next one's beside it, the bands are read one after the other (not refused), to the same result.
TEST(SolveBands, TheNextBandIsReadAheadWhereTwoBandsFramesFit) {
  const fs::path dir = lightstage::testing::scratch_dir();
  const fs::path stack = simulated(dir / "stack", "sphere");
  const io::StackOutline outline = io::read_stack_outline(stack);
  SolveSettings settings = settings_for("l2", "auto");
  const auto plan = [&](std::size_t limit) {
    return plan_bands(outline, limit, coefficient_terms(settings.method),
                      solver_working_bytes(settings, outline.images));
  };
  const BandPlan whole = plan(std::numeric_limits<std::size_t>::max());
  EXPECT_FALSE(whole.read_ahead);
  ASSERT_GT(whole.read_ahead_row_bytes, 0u);
  const BandPlan ahead = plan(whole.fixed_bytes + 5 * (whole.row_bytes + whole.read_ahead_row_bytes));
  EXPECT_TRUE(ahead.read_ahead);
  EXPECT_EQ(ahead.band_rows, 5);
  const std::size_t one_row = whole.fixed_bytes + whole.row_bytes + whole.read_ahead_row_bytes - 1;
  const BandPlan serial = plan(one_row);
  EXPECT_FALSE(serial.read_ahead);
  EXPECT_EQ(serial.band_rows, 1);
  EXPECT_EQ(serial.bands, outline.size.height);
  EXPECT_THAT(error_of([&] { plan(whole.fixed_bytes + whole.row_bytes - 1); }), HasSubstr("--memory-limit"));

  const SolveReport full = solve_folder(stack, settings, dir / "whole");
  settings.memory_limit = std::to_string(one_row);
  const SolveReport banded = solve_folder(stack, settings, dir / "serial");
  EXPECT_EQ(banded.summary["bands"]["read_ahead"], false);
  EXPECT_EQ(banded.summary["bands"]["bands"], outline.size.height);
  EXPECT_EQ(banded.summary["pixels_solved"], full.summary["pixels_solved"]);
  expect_same_map(io::read_exr(dir / "serial" / "normal.exr", {"R", "G", "B"}),
                  io::read_exr(dir / "whole" / "normal.exr", {"R", "G", "B"}), "normals");
  for (const char* file : {"albedo.pfm", "residual.pfm", "confidence.pfm"})
    expect_same_map(io::read_pfm(dir / "serial" / file), io::read_pfm(dir / "whole" / file), file);
}

// rpca decomposes blocks of pixels together: cut from runs of whole rows, which the bands keep whole.
TEST(SolveBands, RpcaDecomposesTheWholeImagesBlocksInBands) {
  const fs::path dir = lightstage::testing::scratch_dir();
  const fs::path stack = simulated(dir / "stack", "bumps");
  SolveSettings rpca = settings_for("rpca", "auto");
  rpca.rpca.block_pixels = 70;  // runs of two or three of the 40-pixel rows: bands of 4 or 5 rows
  expect_bands_equal_whole(stack, rpca, dir, /*bands=*/8);
  const auto summary =
      nlohmann::json::parse(lightstage::testing::read_text(dir / "rpca_bands" / "summary.json"));
  EXPECT_GT(summary["bands"]["bands"].get<int>(), 8) << "every band 5 rows: not cut at the runs";
}

TEST(SolveBands, TheBiPolynomialMethodsAndAutoRefitTheirRelightingOverTheWholeObject) {
  const fs::path dir = lightstage::testing::scratch_dir();
  // Colour, near LEDs and a highlight sharp enough for the refit's specular lobe.
  const fs::path shiny = simulated(dir / "shiny", "shiny-sphere", "0.9,0.6,0.3");
  for (const char* method : {"biquadratic", "auto"})
    expect_bands_equal_whole(shiny, settings_for(method, "auto"), dir / "shiny-out");
  const auto reflectance = nlohmann::json::parse(lightstage::testing::read_text(
      dir / "shiny-out" / "biquadratic_bands" / "summary.json"))["reflectance"];
  EXPECT_GT(reflectance["fit"]["pixels"].get<int>(), 500);
  EXPECT_TRUE(reflectance.contains("specular")) << reflectance.dump();
  const fs::path bumps = simulated(dir / "bumps", "bumps");
  for (const char* method : {"bilinear", "bicubic"})
    expect_bands_equal_whole(bumps, settings_for(method, "auto"), dir / "bumps-out");
  // The fall-off κ the azimuth's biquadratic solve estimates: from every band, as whole.
  SolveSettings monotonic = settings_for("monotonic", "auto");
  monotonic.azimuth_from = "biquadratic";
  monotonic.resolve();
  expect_bands_equal_whole(bumps, monotonic, dir / "bumps-out");
}

TEST(SolveBands, RandomSeedsAndColourFollowThePixelsPlaceInTheWholeImage) {
  const fs::path dir = lightstage::testing::scratch_dir();
  const fs::path stack = simulated(dir / "stack", "sphere", "0.9,0.6,0.3");
  SolveSettings ransac = settings_for("robust", "auto");
  ransac.estimator = "ransac";
  ransac.resolve();
  expect_bands_equal_whole(stack, ransac, dir);
}

TEST(SolveBands, MethodsThatNeedTheWholeImageAndLimitsTooSmallAreRefused) {
  const fs::path dir = lightstage::testing::scratch_dir();
  const fs::path stack = simulated(dir / "stack", "sphere");
  const std::string error = error_of(
      [&] { solve_folder(stack, settings_for("shape-prior", limit_for_rows(stack, 5)), dir / "prior"); });
  EXPECT_THAT(error, HasSubstr("--method shape-prior needs the whole image"));
  EXPECT_THAT(error, HasSubstr("l2, robust, monotonic, rpca, l1, sbl, bilinear, biquadratic, bicubic, auto"));
  EXPECT_FALSE(fs::exists(dir / "prior" / "summary.json"));
  EXPECT_THAT(error_of([&] { solve_folder(stack, settings_for("l2", "4K"), dir / "small"); }),
              HasSubstr("--memory-limit 4.1 kB: too small for this stack (40x36"));
}

TEST(SolveBands, ACropIsTheWholeSolveCutToItsRegionInBandsOrWhole) {
  const fs::path dir = lightstage::testing::scratch_dir();
  const fs::path stack = simulated(dir / "stack", "bumps", "0.9,0.6,0.3");  // near LEDs, colour
  const SolveReport whole = solve_folder(stack, settings_for("l2", "auto"), dir / "whole");
  const cv::Rect region(5, 7, 21, 17);
  const cv::Mat expected = io::read_exr(dir / "whole" / "normal.exr", {"R", "G", "B"})(region);
  for (const bool bands : {false, true}) {
    SCOPED_TRACE(bands ? "bands" : "whole");
    SolveSettings settings = settings_for("l2", bands ? limit_for_rows(stack, 4) : "auto");
    settings.crop = "5,7,21,17";
    settings.band_part_bytes = 3 * 21 * 96 * sizeof(float);  // bands of 4 rows in parts of 3 and 1
    const fs::path out = dir / (bands ? "crop_bands" : "crop_whole");
    const SolveReport crop = solve_folder(stack, settings, out);
    EXPECT_EQ(crop.summary.contains("bands"), bands);
    if (bands) {
      EXPECT_EQ(crop.summary["bands"]["part_rows"], 3);
    }
    EXPECT_EQ(crop.summary["crop"], nlohmann::json({5, 7, 21, 17}));
    EXPECT_EQ(crop.summary["lights"], whole.summary["lights"]);
    expect_same_map(io::read_exr(out / "normal.exr", {"R", "G", "B"}), expected, "normals");
    ASSERT_TRUE(crop.error);
    EXPECT_LT(crop.error->count, whole.error->count);
  }
  SolveSettings bad = settings_for("l2", "auto");
  for (const char* text : {"1,2,3", "1,2,3,4,5", "a,b,c,d", "-1,0,4,4", "0,0,0,4", "1 ,2,3,4"}) {
    bad.crop = text;
    EXPECT_THAT(error_of([&] { bad.resolve(); }), HasSubstr("--crop")) << text;
  }
  bad.crop = "30,0,11,10";
  EXPECT_THAT(error_of([&] { solve_folder(stack, bad, dir / "outside"); }),
              HasSubstr("--crop 30,0,11,10: reaches outside the 40x36 images of"));
  bad = settings_for("shape-prior", "auto");
  bad.crop = "0,0,4,4";
  EXPECT_THAT(error_of([&] { bad.resolve(); }),
              HasSubstr("shape-prior's depth prior covers the whole image"));
}

TEST(SolveBands, MemoryLimitsParseAsPeopleWriteThem) {
  EXPECT_EQ(parse_memory_limit("256M"), std::size_t{256} << 20);
  EXPECT_EQ(parse_memory_limit("1.5G"), std::size_t{3} << 29);
  EXPECT_EQ(parse_memory_limit("4096"), 4096u);
  EXPECT_EQ(parse_memory_limit("2k"), 2048u);
  EXPECT_EQ(parse_memory_limit("auto"), physical_memory_bytes() / 2);
  for (const char* bad : {"", "M", "12X", "-5M", "0", "1.5GB", "nan", "1e400"})
    EXPECT_THAT(error_of([&] { parse_memory_limit(bad); }), HasSubstr("--memory-limit")) << bad;
  SolveSettings settings;
  settings.memory_limit = "lots";
  EXPECT_THAT(error_of([&] { settings.resolve(); }), HasSubstr("'lots' is not a size"));
}

}  // namespace
}  // namespace lightstage::pipeline
