// Issue 18: `solve --memory-limit` keeps a stack that does not fit within the
// limit (the child's peak resident memory, measured), solving it in bands with
// the whole-image result.
#include "lightstage/host/io/exr.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"
#include "lightstage/testing/sanitizers.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>

namespace lightstage {
namespace {

namespace fs = std::filesystem;

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

TEST(LargeStack, SolveKeepsWithinTheMemoryLimitWithTheWholeImageResult) {
  LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY("test_pipeline_solve_bands (the same bands, compared map by map)");
  const fs::path dir = testing::scratch_dir();
  const fs::path stack = dir / "stack";
  // 96 frames of 768x768, 16-bit grey: 113 MB decoded, about 430 MB resident to solve whole.
  auto r = testing::run_lightstage({"simulate", "--quiet", "--rig",
                                    (testing::source_dir() / "hw/rigs/sim-dome.yaml").string(), "--scene",
                                    "bumps", "--width", "768", "--height", "768", "--out", stack.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;

  const std::size_t limit = std::size_t{200} << 20;
  r = testing::run_lightstage({"solve", "--quiet", "--input", stack.string(), "--method", "l2", "--out",
                               (dir / "bands").string(), "--memory-limit", "200M"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto whole = testing::run_lightstage(
      {"solve", "--quiet", "--input", stack.string(), "--method", "l2", "--out", (dir / "whole").string()});
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  const std::size_t banded_rss = r.peak_rss_bytes, whole_rss = whole.peak_rss_bytes;
  std::printf("768x768x96 l2: whole %.0f MB, bands under --memory-limit 200M %.0f MB\n", whole_rss / 1e6,
              banded_rss / 1e6);
  RecordProperty("whole_rss_mb", fmt::format("{:.0f}", whole_rss / 1e6));
  RecordProperty("banded_rss_mb", fmt::format("{:.0f}", banded_rss / 1e6));

  const nlohmann::json summary = read_json(dir / "bands" / "summary.json");
  ASSERT_TRUE(summary.contains("bands"));
  EXPECT_GT(summary["bands"]["bands"].get<int>(), 1);
  EXPECT_GT(whole_rss, limit) << "the stack must not fit the limit whole, or the test shows nothing";
  EXPECT_LE(banded_rss, limit);
  const cv::Mat a = io::read_exr(dir / "bands" / "normal.exr", {"R", "G", "B"});
  const cv::Mat b = io::read_exr(dir / "whole" / "normal.exr", {"R", "G", "B"});
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0);
  EXPECT_EQ(summary["error_vs_ground_truth"],
            read_json(dir / "whole" / "summary.json")["error_vs_ground_truth"]);
}

TEST(LargeStack, TheBiQuadraticSolveAndItsRelightingRefitKeepWithinTheLimitToo) {
  LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY("test_pipeline_solve_bands (the same bands, compared map by map)");
  const fs::path dir = testing::scratch_dir();
  const fs::path stack = dir / "stack";
  // 96 frames of 640x640, 16-bit grey with a highlight: about 300 MB resident to solve whole.
  auto r = testing::run_lightstage(
      {"simulate", "--quiet", "--rig", (testing::source_dir() / "hw/rigs/sim-dome.yaml").string(), "--scene",
       "shiny-sphere", "--width", "640", "--height", "640", "--out", stack.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;

  const std::size_t limit = std::size_t{200} << 20;
  r = testing::run_lightstage({"solve", "--quiet", "--input", stack.string(), "--method", "biquadratic",
                               "--out", (dir / "bands").string(), "--memory-limit", "200M"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto whole = testing::run_lightstage({"solve", "--quiet", "--input", stack.string(), "--method",
                                              "biquadratic", "--out", (dir / "whole").string()});
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  std::printf("640x640x96 biquadratic: whole %.0f MB, bands under --memory-limit 200M %.0f MB\n",
              whole.peak_rss_bytes / 1e6, r.peak_rss_bytes / 1e6);
  RecordProperty("whole_rss_mb", fmt::format("{:.0f}", whole.peak_rss_bytes / 1e6));
  RecordProperty("banded_rss_mb", fmt::format("{:.0f}", r.peak_rss_bytes / 1e6));

  const nlohmann::json summary = read_json(dir / "bands" / "summary.json");
  ASSERT_TRUE(summary.contains("bands"));
  EXPECT_GT(summary["bands"]["bands"].get<int>(), 1);
  EXPECT_GT(whole.peak_rss_bytes, limit)
      << "the stack must not fit the limit whole, or the test shows nothing";
  EXPECT_LE(r.peak_rss_bytes, limit);
  EXPECT_EQ(summary["reflectance"], read_json(dir / "whole" / "summary.json")["reflectance"]);
  for (const auto& file : summary["files"]["brdf"]) {
    const std::string name = file.get<std::string>();
    EXPECT_EQ(testing::read_text(dir / "bands" / name), testing::read_text(dir / "whole" / name)) << name;
  }
  EXPECT_EQ(testing::read_text(dir / "bands" / "normal.exr"),
            testing::read_text(dir / "whole" / "normal.exr"));
}

TEST(LargeStack, SimulateWritesEachFrameAsItIsRenderedWithoutHoldingTheStack) {
  LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY("test_pipeline_simulate (the same files)");
  const fs::path dir = testing::scratch_dir();
  // 96 frames of 640x480, 16-bit RGB: 177 MB decoded; held whole, the simulation took 327 MB.
  const auto r = testing::run_lightstage({"simulate", "--quiet", "--rig",
                                          (testing::source_dir() / "hw/rigs/sim-dome.yaml").string(),
                                          "--scene", "bumps", "--colour", "patches", "--width", "640",
                                          "--height", "480", "--out", (dir / "stack").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::size_t decoded = std::size_t{96} * 640 * 480 * 6;
  std::printf("640x480x96 RGB simulate: %.0f MB peak, frames %.0f MB decoded\n", r.peak_rss_bytes / 1e6,
              decoded / 1e6);
  EXPECT_LT(r.peak_rss_bytes, decoded);
  const nlohmann::json manifest = read_json(dir / "stack" / "manifest.json");
  EXPECT_EQ(manifest["width"], 640);
  EXPECT_EQ(manifest["height"], 480);
  EXPECT_EQ(manifest["frames"].size(), 96u);
  EXPECT_EQ(testing::read_text(dir / "stack" / "filenames.txt").substr(0, 8), "001.png\n");
}

}  // namespace
}  // namespace lightstage
