// `lightstage integrate` and `solve --method shape-prior` end to end through
// the CLI, measured against the simulator's ground truth.
#include "lightstage/common/rig.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/surface/mesh.hpp"
#include "lightstage/sim/natural_capture.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>

namespace lightstage {
namespace {

using testing::run_lightstage;

constexpr int kSize = 96;
const double kPixelMm = 102.4 / kSize;  // the default dome camera's field at kSize pixels

// Mean |a − b − median offset| / range of b over b's nonzero pixels.
double relative_depth_error(const cv::Mat& a, const cv::Mat& b, const cv::Mat& mask) {
  std::vector<double> d;
  for (int r = 0; r < b.rows; ++r)
    for (int c = 0; c < b.cols; ++c)
      if (mask.at<std::uint8_t>(r, c)) d.push_back(a.at<float>(r, c) - b.at<float>(r, c));
  std::vector<double> s = d;
  std::nth_element(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(s.size() / 2), s.end());
  double sum = 0;
  for (const double x : d) sum += std::abs(x - s[s.size() / 2]);
  double lo = 0, hi = 0;
  cv::minMaxLoc(b, &lo, &hi, nullptr, nullptr, mask);
  return sum / static_cast<double>(d.size()) / (hi - lo);
}

TEST(Integrate, SolvedNormalsBecomeDepthAndMeshes) {
  const auto dir = testing::scratch_dir();
  auto run = run_lightstage({"simulate", "--scene", "bumps", "--lights", "distant", "--noise", "none",
                             "--width", std::to_string(kSize), "--height", std::to_string(kSize), "--out",
                             (dir / "stack").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  run = run_lightstage({"solve", "--input", (dir / "stack").string(), "--out", (dir / "result").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  run = run_lightstage({"integrate", "--input", (dir / "result").string(), "--mask",
                        (dir / "stack/mask.png").string(), "--pixel-mm", fmt::format("{}", kPixelMm),
                        "--mesh", "both", "--out", (dir / "surface").string(), "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  for (const char* file : {"depth.pfm", "depth.png", "mesh.ply", "mesh.obj", "surface.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / "surface" / file)) << file;
  const auto summary = nlohmann::json::parse(run.out);
  const cv::Mat depth = io::read_pfm(dir / "surface/depth.pfm");
  const cv::Mat truth = io::read_pfm(dir / "stack/depth_gt.pfm");
  const cv::Mat mask = depth != 0;
  // l2 normals of a noiseless Lambertian stack: the surface is within 1% of the height range.
  EXPECT_LT(relative_depth_error(depth, truth, mask), 0.01);
  const auto mesh = surface::read_ply(dir / "surface/mesh.ply");
  EXPECT_EQ(mesh.vertices.size(), summary["mesh"]["vertices"].get<std::size_t>());
  EXPECT_EQ(mesh.normals.size(), mesh.vertices.size());
  EXPECT_EQ(mesh.colours.size(), mesh.vertices.size());  // albedo.png of the result
  EXPECT_GT(mesh.triangles.size(), mesh.vertices.size());
  // Millimetres: the mesh spans about the bumps' 96 mm square.
  float lo = 1e9f, hi = -1e9f;
  for (const auto& v : mesh.vertices) {
    lo = std::min(lo, v.x());
    hi = std::max(hi, v.x());
  }
  EXPECT_NEAR(hi - lo, 96.0, 4.0);
  EXPECT_EQ(summary["mesh"]["step"], 1) << "a small surface is meshed whole";

  // A vertex every second pixel each way: about a quarter of them, the same extent.
  run = run_lightstage({"integrate", "--input", (dir / "result").string(), "--mask",
                        (dir / "stack/mask.png").string(), "--pixel-mm", fmt::format("{}", kPixelMm),
                        "--mesh-step", "2", "--out", (dir / "coarse").string(), "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto coarse = nlohmann::json::parse(run.out)["mesh"];
  EXPECT_EQ(coarse["step"], 2);
  const double share = coarse["vertices"].get<double>() / summary["mesh"]["vertices"].get<double>();
  EXPECT_NEAR(share, 0.25, 0.02);
}

TEST(Integrate, ShapePriorSolveUnderNaturalLighting) {
  const auto dir = testing::scratch_dir();
  const Rig rig = load_rig(testing::source_dir() / "hw/rigs/sim-dome.yaml");
  sim::SimulateOptions scene;
  scene.scene = "bunny";
  scene.width = scene.height = kSize;
  sim::NaturalCaptureOptions capture;  // random responses per image
  const sim::NaturalCapture natural = sim::simulate_natural(rig, scene, capture);
  io::write_stack(dir / "stack", natural.stack, {{"natural_capture", natural.describe()}});
  const cv::Mat prior = sim::degrade_depth(natural.stack.ground_truth->depth, natural.stack.mask,
                                           sim::PriorDegradation::beta(4), 3);
  io::write_pfm(dir / "prior.pfm", prior);
  auto run = run_lightstage({"solve", "--input", (dir / "stack").string(), "--method", "shape-prior",
                             "--prior", (dir / "prior.pfm").string(), "--pixel-mm",
                             fmt::format("{}", kPixelMm), "--prior-radius", fmt::format("{}", 6 * kPixelMm),
                             "--out", (dir / "result").string(), "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto summary = nlohmann::json::parse(run.out);
  EXPECT_EQ(summary["method"], "shape-prior");
  EXPECT_LT(summary["error_vs_ground_truth"]["mean_deg"].get<double>(), 6.0) << run.out;
  // And fused with the same prior into a surface.
  run = run_lightstage({"integrate", "--input", (dir / "result").string(), "--prior",
                        (dir / "prior.pfm").string(), "--pixel-mm", fmt::format("{}", kPixelMm), "--out",
                        (dir / "surface").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "surface/mesh.ply"));
}

TEST(Integrate, BadInputNamesTheFlagOrFile) {
  const auto dir = testing::scratch_dir();
  auto run = run_lightstage({"integrate", "--out", (dir / "o").string()});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("--normals"), std::string::npos) << run.err;
  run = run_lightstage(
      {"integrate", "--normals", (dir / "missing.png").string(), "--out", (dir / "o").string()});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("missing.png"), std::string::npos) << run.err;
  {
    std::ofstream k(dir / "K.txt");
    k << "1 0 0\n0 1 0\n";
  }
  cv::Mat n(8, 8, CV_16UC3, cv::Scalar(32768, 32768, 65535));
  io::write_png16(dir / "n.png", n);
  run = run_lightstage({"integrate", "--normals", (dir / "n.png").string(), "--intrinsics",
                        (dir / "K.txt").string(), "--out", (dir / "o").string()});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("K.txt: intrinsics: expected nine numbers"), std::string::npos) << run.err;
  for (const char* step : {"0", "two", "1.5"}) {
    run = run_lightstage({"integrate", "--normals", (dir / "n.png").string(), "--mesh-step", step, "--out",
                          (dir / "o").string()});
    EXPECT_NE(run.exit_code, 0);
    EXPECT_NE(run.err.find(std::string("--mesh-step: '") + step + "'"), std::string::npos) << run.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "o" / "depth.pfm")) << "refused before any work";
  }
  run = run_lightstage({"solve", "--input", (dir / "nowhere").string(), "--method", "shape-prior", "--out",
                        (dir / "r").string()});
  EXPECT_NE(run.exit_code, 0);
}

}  // namespace
}  // namespace lightstage
