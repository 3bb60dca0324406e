// The page's requests, read strictly: each bad field refused by name.
#include "lightstage/station/station_requests.hpp"
#include "lightstage/station/operator_access.hpp"

#include <gtest/gtest.h>

namespace lightstage::station {
namespace {

using nlohmann::json;

// The refusal's message (status 400), or "" when the request was accepted.
template <typename Read>
std::string refused(Read read, const json& body) {
  try {
    read(body);
  } catch (const Refused& e) {
    EXPECT_EQ(e.status(), 400) << e.what();
    return e.what();
  }
  return "";
}

bool names(const std::string& message, const std::string& what) {
  return message.find(what) != std::string::npos;
}

TEST(StationRequests, ACaptureRequestRoundTripsAndItsBadFieldsAreNamed) {
  const json body = {{"name", "coin-1"},         {"exposure_us", 4000},  {"dark_frames", 2},
                     {"bracket_stops", {0, -3}}, {"led_ids", {1, 2, 3}}, {"target", "chrome-sphere"}};
  const CaptureRequest request = capture_request(body);
  EXPECT_EQ(request.name, "coin-1");
  EXPECT_EQ(*request.exposure_us, 4000);
  EXPECT_TRUE(request.chrome_sphere);
  // What the station keeps for a resume reads back the same.
  EXPECT_EQ(capture_request(request.to_json()).to_json(), request.to_json());
  EXPECT_FALSE(capture_request({{"name", "a"}, {"exposure_us", "auto"}}).exposure_us);

  EXPECT_TRUE(names(refused(capture_request, {{"exposure_us", 10}}), "'name'"));
  EXPECT_TRUE(names(refused(capture_request, {{"name", "../etc"}}), "capture.name"));
  EXPECT_TRUE(names(refused(capture_request, {{"name", ".hidden"}}), "capture.name"));
  EXPECT_TRUE(names(refused(capture_request, {{"name", std::string(65, 'a')}}), "capture.name"));
  EXPECT_TRUE(names(refused(capture_request, {{"name", "a"}, {"exposure_us", -5}}), "capture.exposure_us"));
  EXPECT_TRUE(
      names(refused(capture_request, {{"name", "a"}, {"exposure_us", "fast"}}), "capture.exposure_us"));
  EXPECT_TRUE(names(refused(capture_request, {{"name", "a"}, {"dark_frames", 1.5}}), "capture.dark_frames"));
  EXPECT_TRUE(names(refused(capture_request, {{"name", "a"}, {"led_ids", "all"}}), "capture.led_ids"));
  EXPECT_TRUE(names(refused(capture_request, {{"name", "a"}, {"target", "moon"}}), "capture.target"));
  EXPECT_TRUE(names(refused(capture_request, {{"name", "a"}, {"exposure", 10}}), "unknown field 'exposure'"));
  EXPECT_TRUE(names(refused(capture_request, json::array()), "JSON object"));
}

TEST(StationRequests, LedsPreviewCalibrationAndSolveRequestsAreChecked) {
  const LedsRequest leds =
      leds_request({{"leds", {{{"id", 3}, {"level", 0.5}}, {{"id", 4}}, {{"id", 5}, {"level", 0}}}}});
  ASSERT_EQ(leds.levels.size(), 2u) << "a level of 0 is an LED left dark";
  EXPECT_EQ(leds.levels[0], std::make_pair(3u, 0.5f));
  EXPECT_EQ(leds.levels[1], std::make_pair(4u, 1.0f));
  EXPECT_TRUE(names(refused(leds_request, {{"leds", {{{"id", 3}}, {{"id", 3}}}}}), "twice"));
  EXPECT_TRUE(names(refused(leds_request, {{"leds", {{{"id", 3}, {"level", 2}}}}}), "leds[].level"));
  EXPECT_TRUE(names(refused(leds_request, {{"leds", {{{"id", -1}}}}}), "leds[].id"));
  EXPECT_TRUE(names(refused(leds_request, json::object()), "'leds'"));

  EXPECT_TRUE(names(refused(preview_request, {{"led", 1}}), "exposure_us"));
  EXPECT_TRUE(names(refused(preview_request, {{"led", 1}, {"exposure_us", 0}}), "preview.exposure_us"));
  EXPECT_EQ(refused(preview_request, {{"led", 1}, {"exposure_us", 1000}, {"gain", 2}}), "");

  const CalibrationRequest calibration = calibration_request({{"name", "cal"}, {"stacks", {"c1", "c2"}}});
  EXPECT_EQ(calibration.stacks.size(), 2u);
  EXPECT_TRUE(names(refused(calibration_request, {{"name", "cal"}, {"stacks", json::array()}}),
                    "calibration.stacks"));
  EXPECT_TRUE(
      names(refused(calibration_request, {{"name", "cal"}, {"stacks", {"a/b"}}}), "calibration.stacks[]"));
  EXPECT_TRUE(names(refused(calibration_request, {{"name", "cal"}, {"stacks", {"c1"}}, {"circle", 1}}),
                    "unknown field 'circle'"));

  const SphereCircle circle = sphere_request({{"x_px", 60}, {"y_px", 62.5}, {"radius_px", 30}});
  EXPECT_EQ(circle.y_px, 62.5);
  EXPECT_TRUE(names(refused(sphere_request, {{"x_px", 1}}), "radius_px"));
  EXPECT_TRUE(
      names(refused(sphere_request, {{"x_px", 1}, {"y_px", 1}, {"radius_px", 0.5}}), "sphere.radius_px"));
  EXPECT_TRUE(names(refused(sphere_request, {{"x_px", -1}, {"y_px", 1}, {"radius_px", 5}}), "sphere.x_px"));

  const SolveRequest solve = solve_request({{"stack", "coin"}, {"method", "robust"}});
  EXPECT_EQ(solve.name, "coin-robust");
  EXPECT_TRUE(names(refused(solve_request, {{"method", "l2"}}), "'stack'"));
  EXPECT_TRUE(
      names(refused(solve_request, {{"stack", "coin"}, {"calibration", "../x"}}), "solve.calibration"));
}

}  // namespace
}  // namespace lightstage::station
