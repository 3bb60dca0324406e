#include "lightstage/host/io/stack_io.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/geometry.hpp"
#include "lightstage/common/version.hpp"
#include "lightstage/testing/paths.hpp"
#include "stack_fixture.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace lightstage {
namespace {

nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

TEST(HostStackIo, WriteThenLoadRoundTripsEverything) {
  const auto dir = testing::scratch_dir() / "stack";
  const ImageStack original = testing::small_stack();
  io::write_stack(dir, original, {{"rig", {{"name", "test-dome"}}}, {"scene", "sphere"}});
  const ImageStack loaded = io::load_stack(dir);

  ASSERT_EQ(loaded.frames.size(), original.frames.size());
  for (std::size_t i = 0; i < loaded.frames.size(); ++i) {
    const Frame& a = original.frames[i];
    const Frame& b = loaded.frames[i];
    EXPECT_EQ(b.filename, a.filename);
    ASSERT_EQ(b.image.type(), a.image.type());
    EXPECT_EQ(cv::norm(a.image, b.image, cv::NORM_INF), 0) << i;
    EXPECT_LT(angle_between_deg(a.light_direction, b.light_direction), 1e-6);
    EXPECT_TRUE(a.light_intensity.isApprox(b.light_intensity, 1e-9));
    EXPECT_EQ(b.led_id, a.led_id);
    EXPECT_EQ(b.led_position_mm.has_value(), a.led_position_mm.has_value());
    if (a.led_position_mm) {
      EXPECT_TRUE(b.led_position_mm->isApprox(*a.led_position_mm));
    }
    EXPECT_EQ(b.exposure_us, a.exposure_us);
    EXPECT_EQ(b.gain, a.gain);
    EXPECT_EQ(b.black_level, a.black_level);
    EXPECT_EQ(b.saturation_level, a.saturation_level);
  }
  EXPECT_EQ(cv::norm(loaded.mask, original.mask, cv::NORM_INF), 0);
  ASSERT_TRUE(loaded.ground_truth.has_value());
  EXPECT_EQ(cv::norm(loaded.ground_truth->depth, original.ground_truth->depth, cv::NORM_INF), 0);
  EXPECT_LT(cv::norm(loaded.ground_truth->normals, original.ground_truth->normals, cv::NORM_INF), 1e-4);

  const auto manifest = read_json(dir / "manifest.json");
  EXPECT_EQ(manifest["format"], "lightstage-stack");
  EXPECT_EQ(manifest["version"], 1);
  EXPECT_EQ(manifest["software"], std::string("lightstage ") + kVersion);
  EXPECT_EQ(manifest["created"].get<std::string>().back(), 'Z');
  EXPECT_EQ(manifest["rig"]["name"], "test-dome");
  EXPECT_EQ(manifest["scene"], "sphere");
  EXPECT_EQ(manifest["ground_truth"]["normals"], "Normal_gt.png");
  EXPECT_EQ(manifest["ground_truth"]["depth"], "depth_gt.pfm");
  EXPECT_EQ(manifest["frames"].size(), 4u);
  EXPECT_EQ(manifest["frames"][1]["file"], "img_01.png");
  EXPECT_EQ(manifest["frames"][1]["led_id"], 11);
  EXPECT_FALSE(manifest["frames"][1].contains("led_position_mm"));
  EXPECT_TRUE(manifest["frames"][2].contains("led_position_mm"));
}

TEST(HostStackIo, EightBitFloatAndMasklessStacksRoundTrip) {
  for (const int type : {CV_8UC1, CV_32FC3}) {
    const auto dir = testing::scratch_dir() / fmt::format("t{}", type);
    ImageStack stack = testing::small_stack(3, type);
    stack.mask.release();
    stack.ground_truth.reset();
    for (auto& frame : stack.frames) frame.filename.clear();  // default names
    io::write_stack(dir, stack);
    const ImageStack loaded = io::load_stack(dir);
    ASSERT_EQ(loaded.frames.size(), 3u);
    EXPECT_EQ(loaded.frames[0].filename, type == CV_32FC3 ? "001.pfm" : "001.png");
    EXPECT_EQ(cv::norm(loaded.frames[2].image, stack.frames[2].image, cv::NORM_INF), 0);
    EXPECT_TRUE(loaded.mask.empty());
    EXPECT_FALSE(loaded.ground_truth.has_value());
    EXPECT_FALSE(std::filesystem::exists(dir / "mask.png"));
  }
}

TEST(HostStackIo, ExtraFramesMergeIntoFrameEntries) {
  const auto dir = testing::scratch_dir();
  const ImageStack stack = testing::small_stack(3);
  nlohmann::json extra = {{"frames", nlohmann::json::array()}};
  for (int i = 0; i < 3; ++i) extra["frames"].push_back({{"timestamp_us", 1000 * i}});
  io::write_stack(dir, stack, extra);
  const auto manifest = read_json(dir / "manifest.json");
  EXPECT_EQ(manifest["frames"][2]["timestamp_us"], 2000);
  EXPECT_EQ(manifest["frames"][2]["led_id"], 12);
}

TEST(HostStackIo, ReservedExtraKeysAreRefusedBeforeWriting) {
  const auto dir = testing::scratch_dir() / "out";
  try {
    io::write_stack(dir, testing::small_stack(3), {{"format", "mine"}});
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("format"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir));
}

TEST(HostStackIo, LoadsDiligentLayoutWithoutManifest) {
  const auto dir = testing::scratch_dir();
  io::write_stack(dir, testing::small_stack(3));
  std::filesystem::remove(dir / "manifest.json");
  std::filesystem::remove(dir / "light_intensities.txt");
  const ImageStack loaded = io::load_stack(dir);
  EXPECT_EQ(loaded.frames[0].led_id, -1);
  EXPECT_EQ(loaded.frames[0].black_level, 0);
  EXPECT_EQ(loaded.frames[0].light_intensity, Vec3::Ones());
}

// Per-pixel darks: each frame names its exposure's dark; the file is written
// once, read once and shared by the frames naming it.
TEST(HostStackIo, DarkFramesRoundTripSharedByTheirFrames) {
  const auto dir = testing::scratch_dir() / "stack";
  ImageStack stack = testing::small_stack(4);
  cv::Mat dark_a(stack.frames[0].image.size(), CV_16UC3), dark_b(stack.frames[0].image.size(), CV_16UC3);
  cv::RNG rng(7);
  rng.fill(dark_a, cv::RNG::UNIFORM, 0, 4000);
  rng.fill(dark_b, cv::RNG::UNIFORM, 0, 4000);
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    stack.frames[i].dark = i < 3 ? dark_a : dark_b;
    stack.frames[i].dark_file = i < 3 ? "dark_1000us.png" : "dark_2000us.png";
  }
  io::write_stack(dir, stack);
  ASSERT_TRUE(std::filesystem::exists(dir / "dark_1000us.png"));
  ASSERT_TRUE(std::filesystem::exists(dir / "dark_2000us.png"));
  const auto manifest = read_json(dir / "manifest.json");
  EXPECT_EQ(manifest["frames"][0]["dark"], "dark_1000us.png");
  EXPECT_EQ(manifest["frames"][3]["dark"], "dark_2000us.png");

  const ImageStack loaded = io::load_stack(dir);
  EXPECT_EQ(loaded.frames[1].dark_file, "dark_1000us.png");
  ASSERT_EQ(loaded.frames[1].dark.type(), CV_16UC3);
  EXPECT_EQ(cv::norm(loaded.frames[1].dark, dark_a, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(loaded.frames[3].dark, dark_b, cv::NORM_INF), 0);
  EXPECT_EQ(loaded.frames[0].dark.data, loaded.frames[2].dark.data) << "one exposure's dark is read once";
  EXPECT_NE(loaded.frames[0].dark.data, loaded.frames[3].dark.data);
}

// Stacks written before darks were named (and DiLiGenT, simulated stacks)
// load without one: radiometry falls back to the scalar black level.
TEST(HostStackIo, ManifestsWithoutDarksLoadWithTheScalarBlackLevel) {
  const auto dir = testing::scratch_dir();
  io::write_stack(dir, testing::small_stack(3));
  const auto manifest = read_json(dir / "manifest.json");
  EXPECT_FALSE(manifest["frames"][0].contains("dark"));
  const ImageStack loaded = io::load_stack(dir);
  EXPECT_TRUE(loaded.frames[0].dark.empty());
  EXPECT_TRUE(loaded.frames[0].dark_file.empty());
  EXPECT_EQ(loaded.frames[0].black_level, 64);
}

TEST(HostStackIo, ADarkWithoutAFileNameOrOfAnotherSizeIsRefusedBeforeWriting) {
  const auto dir = testing::scratch_dir() / "out";
  ImageStack stack = testing::small_stack(3);
  stack.frames[1].dark = cv::Mat(stack.frames[1].image.size(), CV_16UC3, cv::Scalar::all(10));
  EXPECT_THROW(io::write_stack(dir, stack), InputError);
  stack.frames[1].dark_file = "dark.png";
  stack.frames[1].dark = cv::Mat(2, 2, CV_16UC3, cv::Scalar::all(10));
  EXPECT_THROW(io::write_stack(dir, stack), InputError);
  stack.frames[1].dark = cv::Mat(stack.frames[1].image.size(), CV_32FC3, cv::Scalar::all(10));
  EXPECT_THROW(io::write_stack(dir, stack), InputError) << "a float dark must be .pfm";
  EXPECT_FALSE(std::filesystem::exists(dir));
}

}  // namespace
}  // namespace lightstage
