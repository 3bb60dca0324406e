// The aravis: backend through the real library, against aravis's own fake
// GenICam camera (device id "Fake_1" in 0.8, enabled through
// arv_enable_interface("Fake")): enumeration, formats, validation, controls
// with rounding and range errors, software-triggered and free-running frames,
// stop/start and the error paths. The GigE and USB3 interfaces are switched
// off so that no test waits for a network discovery.
#include "gphoto2_leaks.hpp"
#include "lightstage/common/camera.hpp"
#include "lightstage/hw/cameras.hpp"
#include "lightstage/hw/probe.hpp"

#include <arv.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace lightstage::hw {
namespace {

using camera::CameraError;
using ::testing::HasSubstr;
using namespace std::chrono_literals;

constexpr const char* kFake = "aravis:Fake_1";

class AravisFake : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    arv_enable_interface("Fake");
    arv_disable_interface("GigEVision");
    arv_disable_interface("USB3Vision");
  }

  static std::unique_ptr<camera::Camera> open(const std::string& uri = kFake) { return open_camera(uri); }

  // A valid configuration of `format`, `width` x `height` in `trigger` mode.
  static camera::CameraConfig config(camera::Camera& cam, const std::string& format, int width, int height,
                                     camera::TriggerMode trigger) {
    camera::CameraConfig c = cam.default_config();
    c.pixel_format = format;
    c.size = {width, height};
    c.trigger = trigger;
    EXPECT_EQ(cam.validate(c).status, camera::ConfigStatus::kValid);
    return c;
  }
};

TEST_F(AravisFake, EnumeratedByTheSchemeAndTheProbe) {
  const auto cameras = list_cameras();
  const auto it = std::find_if(cameras.begin(), cameras.end(),
                               [](const camera::CameraInfo& c) { return c.uri == kFake; });
  ASSERT_NE(it, cameras.end());
  EXPECT_THAT(it->model, HasSubstr("Fake"));
  EXPECT_THAT(it->driver, HasSubstr("aravis"));
  const auto reports = probe_devices();
  const auto report =
      std::find_if(reports.begin(), reports.end(), [](const ProbeReport& r) { return r.scheme == "aravis"; });
  ASSERT_NE(report, reports.end());
  ASSERT_FALSE(report->devices.empty());
  EXPECT_EQ(report->devices.front().uri, kFake);
}

TEST_F(AravisFake, OpensAndDescribesItself) {
  auto cam = open();
  EXPECT_EQ(cam->info().uri, kFake);
  EXPECT_EQ(cam->info().model, "Aravis Fake");
  EXPECT_THAT(cam->info().driver, HasSubstr("aravis 0.8."));
  std::vector<std::string> names;
  for (const auto& f : cam->formats()) {
    names.push_back(f.pixel_format);
    ASSERT_EQ(f.sizes.size(), 1u);
    EXPECT_EQ(f.sizes[0].max, (camera::Size{2048, 2048}));
  }
  // Mono8, Mono16 and the four 8-bit Bayer patterns; not RGB8.
  EXPECT_THAT(names, ::testing::UnorderedElementsAre("GREY", "Y16", "SRGGB8", "SBGGR8", "SGRBG8", "SGBRG8"));
  EXPECT_THAT(cam->trigger_modes(),
              ::testing::ElementsAre(camera::TriggerMode::kFreeRun, camera::TriggerMode::kSoftware,
                                     camera::TriggerMode::kHardware));
  const camera::CameraConfig def = cam->default_config();
  EXPECT_EQ(def.pixel_format, "GREY");
  EXPECT_EQ(def.size, (camera::Size{512, 512}));
  camera::CameraConfig copy = def;
  EXPECT_EQ(cam->validate(copy).status, camera::ConfigStatus::kValid);
}

TEST_F(AravisFake, AnEmptyIdIsTheFirstCamera) { EXPECT_EQ(open("aravis:")->info().model, "Aravis Fake"); }

TEST_F(AravisFake, AnUnknownIdIsNotFoundAndListsTheCameras) {
  try {
    open("aravis:NoSuchCamera-42");
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_EQ(e.kind(), CameraError::Kind::kNotFound);
    EXPECT_THAT(e.what(), HasSubstr("aravis:NoSuchCamera-42"));
    EXPECT_THAT(e.what(), HasSubstr("cameras: aravis:Fake_1"));
  }
  EXPECT_THROW(open("aravis:Fake_1?exposure=3"), InputError);
}

TEST_F(AravisFake, ValidateAdjustsAndRefuses) {
  auto cam = open();
  camera::CameraConfig c = cam->default_config();
  c.pixel_format = "Y10";
  camera::Validation v = cam->validate(c);
  EXPECT_EQ(v.status, camera::ConfigStatus::kInvalid);
  EXPECT_THAT(v.message(), HasSubstr("Y10"));

  c = cam->default_config();
  c.size = {5000, 100};
  c.roi = camera::Roi{4000, 0, 64, 64};
  c.buffer_count = 1;
  v = cam->validate(c);
  EXPECT_EQ(v.status, camera::ConfigStatus::kAdjusted) << v.message();
  EXPECT_EQ(c.size, (camera::Size{2048, 100}));
  EXPECT_EQ(c.roi, (camera::Roi{2047, 0, 1, 64}));
  EXPECT_EQ(c.buffer_count, 2);

  auto other_line = open("aravis:Fake_1?trigger_line=Line7");
  c = other_line->default_config();
  c.trigger = camera::TriggerMode::kHardware;
  v = other_line->validate(c);
  EXPECT_EQ(v.status, camera::ConfigStatus::kInvalid);
  EXPECT_THAT(v.message(), HasSubstr("Line7"));
}

TEST_F(AravisFake, ExposureRoundsToTheCameraAndRangesAreErrors) {
  auto cam = open();
  const camera::ControlInfo info = cam->control_info();
  EXPECT_DOUBLE_EQ(info.exposure_min_us, 10);
  EXPECT_DOUBLE_EQ(info.exposure_max_us, 1e7);
  EXPECT_EQ(info.latency_frames, 1);
  EXPECT_DOUBLE_EQ(*cam->set_controls({.exposure_us = 1000}).exposure_us, 1000);
  // The fake keeps whole microseconds: what it holds is what comes back.
  EXPECT_DOUBLE_EQ(*cam->set_controls({.exposure_us = 1234.6}).exposure_us, 1234);
  try {
    cam->set_controls({.exposure_us = 5});
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_THAT(e.what(), HasSubstr(kFake));
    EXPECT_THAT(e.what(), HasSubstr("exposure_us 5 is outside the camera's range [10, 10000000]"));
  }
}

TEST_F(AravisFake, RawGainNeedsItsUnitThenRoundsToWholeSteps) {
  auto plain = open();
  try {
    plain->set_controls({.analogue_gain = 2.0});
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_EQ(e.kind(), CameraError::Kind::kUnsupported);
    EXPECT_THAT(e.what(), HasSubstr("gain_raw_db"));
  }
  // With 1 dB per GainRaw step, the fake's 0..10 is 0..10 dB.
  auto cam = open("aravis:Fake_1?gain_raw_db=1");
  EXPECT_DOUBLE_EQ(cam->control_info().gain_min, 1.0);
  EXPECT_NEAR(cam->control_info().gain_max, std::pow(10.0, 0.5), 1e-12);
  const double gain = *cam->set_controls({.analogue_gain = 2.0}).analogue_gain;  // 6.02 dB -> 6 dB
  EXPECT_NEAR(gain, std::pow(10.0, 6.0 / 20), 1e-12);
  try {
    cam->set_controls({.analogue_gain = 4.0});
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_THAT(e.what(), HasSubstr("analogue_gain 4 is outside"));
  }
}

TEST_F(AravisFake, SoftwareTriggerDeliversOneFrameOfTheConfiguredKind) {
  auto cam = open();
  cam->set_controls({.exposure_us = 1000});
  cam->configure(config(*cam, "GREY", 64, 48, camera::TriggerMode::kSoftware));
  EXPECT_THROW(cam->trigger(), CameraError);  // before start()
  cam->start();
  EXPECT_FALSE(cam->wait_frame(150ms));  // nothing without a trigger
  const std::int64_t before = camera::clock_now_ns(camera::ClockDomain::kRealtime);
  cam->trigger();
  const camera::Frame f = cam->capture(3s);
  const std::int64_t after = camera::clock_now_ns(camera::ClockDomain::kRealtime);
  EXPECT_EQ(f.image.cols, 64);
  EXPECT_EQ(f.image.rows, 48);
  EXPECT_EQ(f.image.type(), CV_8UC1);
  EXPECT_EQ(f.pixel_format, "GREY");
  EXPECT_EQ(f.bit_depth, 8);
  EXPECT_EQ(f.clock, camera::ClockDomain::kRealtime);
  EXPECT_EQ(f.timestamp_point, camera::TimestampPoint::kEndOfFrame);
  EXPECT_GE(f.timestamp_ns, before);  // aravis stamps with g_get_real_time()
  EXPECT_LE(f.timestamp_ns, after);
  EXPECT_DOUBLE_EQ(f.exposure_us, 1000);
  EXPECT_FALSE(f.controls_reported);
  EXPECT_FALSE(cam->wait_frame(150ms));  // one trigger, one frame
  try {
    cam->configure(cam->configuration());
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_THAT(e.what(), HasSubstr("while streaming"));
  }
  cam->stop();
}

TEST_F(AravisFake, FreeRunStreamsAndRestarts) {
  auto cam = open();
  cam->set_controls({.exposure_us = 1000});
  cam->configure(config(*cam, "Y16", 128, 96, camera::TriggerMode::kFreeRun));
  EXPECT_THROW(cam->wait_frame(10ms), CameraError);  // not streaming
  cam->start();
  EXPECT_TRUE(cam->streaming());
  try {
    cam->trigger();
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_EQ(e.kind(), CameraError::Kind::kUnsupported);
    EXPECT_THAT(e.what(), HasSubstr("software"));
  }
  const camera::Frame a = cam->capture(3s);
  const camera::Frame b = cam->capture(3s);
  EXPECT_GT(b.sequence, a.sequence);
  EXPECT_GE(b.timestamp_ns, a.timestamp_ns);
  EXPECT_EQ(a.image.type(), CV_16UC1);
  EXPECT_EQ(a.image.cols, 128);
  EXPECT_EQ(a.bit_depth, 16);
  cam->stop();
  cam->stop();  // idempotent
  EXPECT_FALSE(cam->streaming());
  cam->start();
  EXPECT_EQ(cam->capture(3s).image.rows, 96);
  cam->stop();
}

TEST_F(AravisFake, RoiOnTheSensorOrOnTheHost) {
  auto cam = open();
  cam->set_controls({.exposure_us = 1000});
  // Even offsets: the camera windows itself (OffsetX/OffsetY).
  camera::CameraConfig c = config(*cam, "GREY", 256, 256, camera::TriggerMode::kFreeRun);
  c.roi = camera::Roi{16, 8, 64, 32};
  ASSERT_EQ(cam->validate(c).status, camera::ConfigStatus::kValid);
  cam->configure(c);
  cam->start();
  camera::Frame f = cam->capture(3s);
  EXPECT_EQ(f.image.cols, 64);
  EXPECT_EQ(f.image.rows, 32);
  cam->stop();
  // Odd offsets on a Bayer format: cropped on the host, the pattern follows.
  c = config(*cam, "SRGGB8", 256, 256, camera::TriggerMode::kFreeRun);
  c.roi = camera::Roi{1, 1, 32, 30};
  ASSERT_EQ(cam->validate(c).status, camera::ConfigStatus::kValid);
  cam->configure(c);
  cam->start();
  f = cam->capture(3s);
  EXPECT_EQ(f.image.cols, 32);
  EXPECT_EQ(f.image.rows, 30);
  EXPECT_EQ(f.cfa, camera::Cfa::kBGGR);
  cam->stop();
}

}  // namespace
}  // namespace lightstage::hw
