// calibration.json and .lp files: what is written reads back the same, and
// every malformed field is named in the error.
#include "lightstage/host/calibration/light_calibration.hpp"
#include "lightstage/host/calibration/lp_file.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

namespace lightstage::calibration {
namespace {

using testing::error_of;

LightCalibration sample() {
  LightCalibration c;
  c.camera = CameraGeometry::unknown(64, 48);
  c.camera.pixel_pitch_mm = 0.5;
  c.camera.metric = true;
  c.object_position_mm = Vec3(0, 0, 5);
  c.direction_method = "triangulated";
  c.dome_radius_mm = 400;
  for (int i = 0; i < 3; ++i) {
    CalibratedLight light;
    light.image = fmt::format("{:03}.png", i + 1);
    light.led_id = 10 + i;
    light.measured = i != 1;
    light.direction = Vec3(0.1 * i, 0.2, 1).normalized();
    light.position_mm = Vec3(10.0 * i, 20, 390);
    light.intensity = 0.9 + 0.1 * i;
    c.lights.push_back(light);
  }
  c.problems.push_back("002.png: missing");
  return c;
}

TEST(CalibrationFile, RoundTripsThroughJsonOnDisk) {
  const auto path = testing::scratch_dir() / "calibration.json";
  write_calibration(path, sample());
  const LightCalibration back = read_calibration(path);
  const LightCalibration original = sample();
  ASSERT_EQ(back.lights.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back.lights[i].image, original.lights[i].image);
    EXPECT_EQ(back.lights[i].led_id, original.lights[i].led_id);
    EXPECT_EQ(back.lights[i].measured, original.lights[i].measured);
    EXPECT_LT((back.lights[i].direction - original.lights[i].direction).norm(), 1e-12);
    ASSERT_TRUE(back.lights[i].position_mm);
    EXPECT_LT((*back.lights[i].position_mm - *original.lights[i].position_mm).norm(), 1e-9);
    EXPECT_DOUBLE_EQ(back.lights[i].intensity, original.lights[i].intensity);
  }
  EXPECT_EQ(back.camera.width, 64);
  EXPECT_DOUBLE_EQ(back.camera.pixel_pitch_mm, 0.5);
  EXPECT_TRUE(back.camera.metric);
  EXPECT_EQ(back.direction_method, "triangulated");
  EXPECT_EQ(back.object_position_mm, Vec3(0, 0, 5));
  EXPECT_EQ(back.problems.size(), 1u);
  EXPECT_EQ(directions_text(back).size(), directions_text(original).size());
  // Only measured lights go to the text files.
  const std::string intensities = intensities_text(back);
  EXPECT_EQ(std::count(intensities.begin(), intensities.end(), '\n'), 2);
}

TEST(CalibrationFile, ErrorsNameTheFieldAndValue) {
  nlohmann::json good = to_json(sample());
  auto broken = [&](const std::function<void(nlohmann::json&)>& change) {
    nlohmann::json j = good;
    change(j);
    return error_of([&] { calibration_from_json(j, "cal.json"); });
  };
  EXPECT_NE(broken([](auto& j) { j["format"] = "other"; }).find("cal.json: format"), std::string::npos);
  EXPECT_NE(broken([](auto& j) { j["version"] = 99; }).find("version: unsupported value 99"),
            std::string::npos);
  EXPECT_NE(broken([](auto& j) { j.erase("lights"); }).find("cal.json.lights: missing"), std::string::npos);
  EXPECT_NE(broken([](auto& j) {
              j["lights"][2]["direction"] = {1, 2};
            }).find("lights[2].direction: expected [x, y, z]"),
            std::string::npos);
  EXPECT_NE(
      broken([](auto& j) { j["lights"][0]["intensity"] = -1; }).find("lights[0].intensity: must be positive"),
      std::string::npos);
  EXPECT_NE(broken([](auto& j) {
              j["lights"][0]["direction"] = {0, 0, 3};
            }).find("expected a unit vector"),
            std::string::npos);
  EXPECT_NE(broken([](auto& j) { j["camera"]["pixel_pitch_mm"] = 0; }).find("camera"), std::string::npos);
  EXPECT_NE(broken([](auto& j) { j["lights"] = nlohmann::json::array(); }).find("non-empty array"),
            std::string::npos);
  EXPECT_NE(broken([](auto& j) { j = nlohmann::json::array(); }).find("top level"), std::string::npos);
  const auto missing = testing::scratch_dir() / "nope.json";
  EXPECT_NE(error_of([&] { read_calibration(missing); }).find("nope.json: cannot open"), std::string::npos);
}

TEST(LpFile, FormatsAndParsesRtiLightPositions) {
  const std::vector<LpEntry> entries = {{"001.png", Vec3(0.1, 0.2, 0.97).normalized()},
                                        {"my image.png", Vec3(-0.5, 0, 0.8).normalized()}};
  const std::string text = format_lp(entries);
  EXPECT_EQ(text.substr(0, 2), "2\n");
  const auto back = parse_lp(text, "a.lp");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[1].filename, "my image.png");
  EXPECT_LT((back[1].direction - entries[1].direction).norm(), 1e-8);
  // CRLF and Windows paths, as RTIBuilder writes them.
  const auto windows = parse_lp("1\r\nC:\\rti\\img 01.jpg 0.0 0.6 0.8\r\n", "w.lp");
  EXPECT_EQ(windows[0].filename, "C:\\rti\\img 01.jpg");
}

TEST(LpFile, ErrorsNameFileAndLine) {
  EXPECT_NE(error_of([] { parse_lp("", "e.lp"); }).find("e.lp: empty"), std::string::npos);
  EXPECT_NE(error_of([] { parse_lp("two\n", "e.lp"); }).find("e.lp:1: the first line"), std::string::npos);
  EXPECT_NE(
      error_of([] { parse_lp("2\na.png 0 0 1\n", "e.lp"); }).find("1 light line(s), but line 1 announces 2"),
      std::string::npos);
  EXPECT_NE(error_of([] { parse_lp("1\na.png 0 x 1\n", "e.lp"); }).find("e.lp:2: 'x' is not a finite number"),
            std::string::npos);
  EXPECT_NE(error_of([] { parse_lp("1\na.png 0 0 0\n", "e.lp"); }).find("e.lp:2: zero-length"),
            std::string::npos);
  EXPECT_NE(error_of([] { parse_lp("1\na.png 0 0 1\nb.png 0 0 1\n", "e.lp"); }).find("e.lp:3: more lights"),
            std::string::npos);
  EXPECT_NE(error_of([] { parse_lp("1\n0 0 1\n", "e.lp"); }).find("expected 'filename x y z'"),
            std::string::npos);
}

}  // namespace
}  // namespace lightstage::calibration
