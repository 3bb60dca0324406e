// Issue 20, colour: a simulated object with a colour albedo texture (sensor
// noise on) is solved without some of its lights and relit at them; the relit
// colour images must have the chromaticity of the renderer's noise-free
// frames (mean within 2 %), the solve keeps a colour albedo and the surface's
// mesh its colours.
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"
#include "lightstage/testing/sanitizers.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <set>
#include <sstream>
#include <string_view>

namespace lightstage {
namespace {

namespace fs = std::filesystem;

void expect_ok(const testing::RunResult& r, const std::string& what) {
  ASSERT_EQ(r.exit_code, 0) << what << "\n" << r.out << r.err;
}

// Linear (r, g, b) of a photograph's pixel, as the radiometry reads it.
cv::Vec3d photo_rgb(const Frame& frame, cv::Point at) {
  const cv::Vec3w raw = frame.image.at<cv::Vec3w>(at);
  cv::Vec3d rgb;
  for (int c = 0; c < 3; ++c) rgb[c] = (raw[2 - c] - frame.black_level) / 65535.0 / frame.light_intensity[c];
  return rgb;
}

struct Chromaticity {
  double mean_error = 0;  // mean over lit pixels of Σ_c |c_relit − c_photo|, c = rgb / (r + g + b)
  std::size_t pixels = 0;
};

// Solves `stack_dir` without `held_out` with `method`, relights at those
// lights and compares the colours with the renderer's noise-free frames of
// them (`truth_dir`: the same scene without noise).
Chromaticity held_out_chromaticity(const fs::path& dir, const fs::path& stack_dir, const fs::path& truth_dir,
                                   const std::string& method, const std::set<std::size_t>& held_out) {
  const ImageStack stack = io::load_stack(stack_dir);
  const ImageStack truth = io::load_stack(truth_dir);
  ImageStack fit = stack;
  fit.frames.clear();
  std::vector<Frame> photos;
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    if (held_out.count(i))
      photos.push_back(truth.frames[i]);
    else
      fit.frames.push_back(stack.frames[i]);
  }
  io::write_stack(dir / "fit", fit);
  const auto r = testing::run_lightstage(
      {"solve", "--input", (dir / "fit").string(), "--method", method, "--out", (dir / method).string()});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  std::vector<std::string> relight = {"relight",
                                      "--input",
                                      (dir / method).string(),
                                      "--scale",
                                      "4",
                                      "--out",
                                      (dir / (method + "-relit")).string()};
  for (const Frame& photo : photos) {
    const Vec3 l = photo.light_direction.normalized();
    relight.push_back("--light");
    relight.push_back(fmt::format("{:.9f},{:.9f},{:.9f}", l.x(), l.y(), l.z()));
  }
  const auto relit_run = testing::run_lightstage(relight);
  EXPECT_EQ(relit_run.exit_code, 0) << relit_run.out << relit_run.err;
  Chromaticity result;
  for (std::size_t k = 0; k < photos.size(); ++k) {
    const cv::Mat relit = io::read_image(dir / (method + "-relit") / fmt::format("relit_{:03d}.png", k));
    EXPECT_EQ(relit.type(), CV_16UC3) << "relit in colour";
    if (relit.type() != CV_16UC3) return result;
    for (int y = 0; y < relit.rows; ++y) {
      for (int x = 0; x < relit.cols; ++x) {
        if (!stack.mask.empty() && stack.mask.at<std::uint8_t>(y, x) == 0) continue;
        const cv::Vec3w raw = photos[k].image.at<cv::Vec3w>(y, x);
        if (std::max({raw[0], raw[1], raw[2]}) >= photos[k].saturation_level) continue;  // clipped: no colour
        const cv::Vec3d photo = photo_rgb(photos[k], {x, y});
        const cv::Vec3w v = relit.at<cv::Vec3w>(y, x);
        const cv::Vec3d mine(v[2], v[1], v[0]);
        const double photo_sum = photo[0] + photo[1] + photo[2];
        const double mine_sum = mine[0] + mine[1] + mine[2];
        if (photo_sum < 0.15 || mine_sum <= 0) continue;  // lit pixels: shadows carry no colour
        double error = 0;
        for (int c = 0; c < 3; ++c) error += std::abs(mine[c] / mine_sum - photo[c] / photo_sum);
        result.mean_error += error;
        ++result.pixels;
      }
    }
  }
  if (result.pixels > 0) result.mean_error /= static_cast<double>(result.pixels);
  return result;
}

class ColourRelighting : public ::testing::TestWithParam<std::pair<const char*, const char*>> {};

TEST_P(ColourRelighting, HeldOutLightsKeepThePhotographsChromaticity) {
  const auto [material, method] = GetParam();
  if (std::string_view(method) != "l2") LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY("the l2 case");
  const fs::path dir = testing::scratch_dir();
  const std::vector<std::string> scene = {"simulate",
                                          "--scene",
                                          "sphere",
                                          "--material",
                                          material,
                                          "--colour",
                                          "{type: patches, period_mm: 12, saturation: 0.6}",
                                          "--lights",
                                          "distant",
                                          "--width",
                                          "96",
                                          "--height",
                                          "96"};
  const auto simulate = [&](const fs::path& out, const std::string& noise) {
    std::vector<std::string> args = scene;
    args.insert(args.end(), {"--noise", noise, "--out", out.string()});
    expect_ok(testing::run_lightstage(args), "simulate --noise " + noise);
  };
  simulate(dir / "stack", "physical");
  simulate(dir / "truth", "none");
  const Chromaticity c =
      held_out_chromaticity(dir, dir / "stack", dir / "truth", method, {5, 23, 41, 59, 77});
  RecordProperty("mean_chromaticity_error", std::to_string(c.mean_error));
  std::printf("%s, %s: mean chromaticity error %.4f over %zu lit pixels\n", material, method, c.mean_error,
              c.pixels);
  EXPECT_GT(c.pixels, 5000u);
  EXPECT_LT(c.mean_error, 0.02);

  // The solve keeps the colour albedo, and a mesh of it its colours.
  const fs::path result = dir / method;
  EXPECT_EQ(io::read_image(result / "albedo_rgb.png").type(), CV_16UC3);
  expect_ok(testing::run_lightstage({"integrate", "--input", result.string(), "--mesh", "obj", "--out",
                                     (dir / "surface").string()}),
            "integrate");
  std::ifstream obj(dir / "surface" / "mesh.obj");
  ASSERT_TRUE(obj.good());
  std::string tag;
  double x, y, z, red, green, blue;
  std::size_t vertices = 0, coloured = 0;
  for (std::string line; std::getline(obj, line);) {
    std::istringstream in(line);
    if (!(in >> tag >> x >> y >> z >> red >> green >> blue) || tag != "v") continue;
    ++vertices;
    if (std::max({std::abs(red - green), std::abs(green - blue), std::abs(red - blue)}) > 0.05) ++coloured;
  }
  EXPECT_GT(vertices, 1000u);
  EXPECT_GT(coloured, vertices / 2) << "vertex colours follow the albedo's colour";
}

INSTANTIATE_TEST_SUITE_P(Materials, ColourRelighting,
                         ::testing::Values(std::make_pair("lambert", "l2"),
                                           std::make_pair("cook-torrance:roughness=0.3,ks=0.3",
                                                          "biquadratic")),
                         [](const auto& param_info) { return std::string(param_info.param.second); });

}  // namespace
}  // namespace lightstage
