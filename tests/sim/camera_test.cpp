// The virtual camera: exposure windows over the chip's timeline, and the
// camera service behind the host's `sim:` camera backend.
#include "lightstage/common/clock.hpp"
#include "lightstage/common/socket_link.hpp"
#include "lightstage/sim/camera/camera_service.hpp"
#include "lightstage/sim/camera/exposure_tracker.hpp"
#include "lightstage/sim/camera/sim_camera.hpp"
#include "lightstage/sim/gpio/virtual_chip.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <thread>

namespace lightstage::sim {
namespace {

using gpio::TimelineEntry;
using std::chrono::milliseconds;

TimelineEntry led(std::int64_t t, int id, int value) {
  return {t, "LED" + std::to_string(id), value, id, ""};
}

double share_of(const std::vector<std::pair<int, double>>& shares, int id) {
  for (const auto& [led_id, share] : shares) {
    if (led_id == id) return share;
  }
  return 0;
}

TEST(ExposureTracker, SharesOfTheWindowEachLedWasLit) {
  std::vector<std::int64_t> triggers;
  ExposureTracker tracker("TRIGGER", [&](std::int64_t t) { triggers.push_back(t); });
  const std::vector<TimelineEntry> entries = {
      led(0, 1, 1),
      led(100, 2, 1),
      led(150, 2, 0),  // 2: half of [100, 200]
      {100, "TRIGGER", 1, -1, ""},
      {110, "TRIGGER", 0, -1, ""},
      led(300, 1, 0),  // 1: on since before the window, off after it
      led(190, 3, 1),
      led(195, 3, 0),
      led(198, 3, 1),
      led(250, 3, 0),  // 3: 5 + 2 of 100
      led(500, 4, 1),  // 4: after the window
  };
  tracker.record(entries);
  EXPECT_EQ(triggers, std::vector<std::int64_t>{100});
  const auto shares = tracker.lit_shares(100, 200);
  EXPECT_DOUBLE_EQ(share_of(shares, 1), 1.0);
  EXPECT_DOUBLE_EQ(share_of(shares, 2), 0.5);
  EXPECT_DOUBLE_EQ(share_of(shares, 3), 0.07);
  EXPECT_DOUBLE_EQ(share_of(shares, 4), 0.0);
  EXPECT_EQ(shares.size(), 3u);
  EXPECT_EQ(tracker.latest_ns(), 500);
  // Forgetting the past keeps what is needed to know the state at the cut.
  tracker.forget_before(250);
  EXPECT_DOUBLE_EQ(share_of(tracker.lit_shares(260, 360), 1), 0.4);
  EXPECT_DOUBLE_EQ(share_of(tracker.lit_shares(260, 360), 3), 0.0);
}

// A small world, a virtual chip feeding the camera, and the camera served on a socket.
class VirtualCameraTest : public ::testing::Test {
 protected:
  void SetUp() override {
    rig_ = load_rig(testing::source_dir() / "hw/rigs/sim-dome.yaml");
    SimulateOptions options;
    options.scene = "matte-sphere";
    options.light_model = LightModel::kDistant;
    options.width = options.height = 40;
    options.threads = 1;
    options.sensor.noise = NoiseModel::kNone;
    world_ = std::make_shared<World>(rig_, options);
    chip_ = std::make_shared<gpio::VirtualChip>(gpio::layout_from_rig(rig_), gpio::chip_options_for(rig_));
    CameraServiceOptions camera_options;
    camera_options.trigger_delay_ns = 100'000;
    service_ = std::make_shared<CameraService>(world_, options.sensor, camera_options);
    chip_->add_timeline_sink(service_->tracker());
    socket_ = (testing::socket_dir() /
               (std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + ".sock"))
                  .string();
    host_.add(listen_socket_link("unix:" + socket_), service_);
    client_ = chip_->connect();
    const std::vector<unsigned> lines = {*chip_->layout().resolve("LED0"), *chip_->layout().resolve("LED1"),
                                         *chip_->layout().trigger};
    chip_->request_lines(client_, lines, true, "test", {}, {}, monotonic_now_ns());
  }
  void TearDown() override { host_.stop(); }

  void set(const std::string& line, int value, std::int64_t t) {
    const unsigned offset = *chip_->layout().resolve(line);
    const int values[] = {value};
    chip_->set_values(client_, std::span(&offset, 1), values, t);
  }

  // The noiseless frame of `leds` (rig index, weight) at the camera's exposure.
  cv::Mat expected(const std::vector<std::pair<std::size_t, double>>& leds, double exposure_us) const {
    SensorOptions sensor;
    sensor.noise = NoiseModel::kNone;
    sensor.exposure_us = exposure_us;
    return Sensor(sensor, rig_.camera).expose(world_->render(leds), 1, 0);
  }

  Rig rig_;
  std::shared_ptr<World> world_;
  std::shared_ptr<gpio::VirtualChip> chip_;
  std::shared_ptr<CameraService> service_;
  ServiceHost host_;
  std::string socket_;
  gpio::ClientId client_ = 0;
};

TEST_F(VirtualCameraTest, HardwareTriggerSeesTheLedsOnDuringTheExposure) {
  auto cam = open_sim_camera(socket_);
  auto config = cam->default_config();
  config.trigger = lightstage::camera::TriggerMode::kHardware;
  ASSERT_EQ(cam->validate(config).status, lightstage::camera::ConfigStatus::kValid);
  cam->configure(config);
  cam->set_controls({2000.0, std::nullopt});
  cam->start();
  // LED0 lit for the whole exposure, LED1 for its second half.
  const std::int64_t t0 = monotonic_now_ns();
  set("LED0", 1, t0);
  set("TRIGGER", 1, t0 + 1'000'000);
  set("TRIGGER", 0, t0 + 1'050'000);
  const std::int64_t start = t0 + 1'100'000, end = start + 2'000'000;
  set("LED1", 1, start + 1'000'000);
  set("LED0", 0, end + 10'000);
  set("LED1", 0, end + 10'000);
  const auto frame = cam->wait_frame(milliseconds(3000));
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->timestamp_ns, start);
  EXPECT_EQ(frame->clock, lightstage::camera::ClockDomain::kMonotonic);
  EXPECT_DOUBLE_EQ(frame->exposure_us, 2000.0);
  ASSERT_EQ(frame->image.type(), CV_16UC1);
  const cv::Mat want = expected({{0, 1.0}, {1, 0.5}}, 2000.0);
  EXPECT_EQ(cv::norm(frame->image, want, cv::NORM_INF), 0) << "the frame is the scene lit as recorded";
  EXPECT_GT(cv::mean(frame->image)[0], 0);
  // Nothing else was triggered.
  EXPECT_FALSE(cam->wait_frame(milliseconds(100)));
}

TEST_F(VirtualCameraTest, SoftwareTriggerAndRoi) {
  auto cam = open_sim_camera(socket_);
  auto config = cam->default_config();
  config.trigger = lightstage::camera::TriggerMode::kSoftware;
  config.roi = lightstage::camera::Roi{10, 5, 20, 30};
  cam->configure(config);
  cam->start();
  set("LED1", 1, monotonic_now_ns());
  cam->trigger();
  const auto frame = cam->wait_frame(milliseconds(3000));
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->image.cols, 20);
  EXPECT_EQ(frame->image.rows, 30);
  const cv::Mat full = expected({{1, 1.0}}, rig_.camera.exposure_us);
  EXPECT_EQ(cv::norm(frame->image, full(cv::Rect(10, 5, 20, 30)), cv::NORM_INF), 0);
  EXPECT_THROW(cam->set_controls({0.5, std::nullopt}), lightstage::camera::CameraError);
}

TEST_F(VirtualCameraTest, BadRequestsAreCameraErrors) {
  auto cam = open_sim_camera(socket_);
  auto config = cam->default_config();
  config.roi = lightstage::camera::Roi{30, 30, 20, 20};
  EXPECT_EQ(cam->validate(config).status, lightstage::camera::ConfigStatus::kInvalid);
  EXPECT_THROW(cam->configure(config), lightstage::camera::CameraError);
  EXPECT_THROW(cam->trigger(), lightstage::camera::CameraError) << "not in software mode";
  EXPECT_THROW(cam->wait_frame(milliseconds(10)), lightstage::camera::CameraError) << "not streaming";
  // One client at a time.
  EXPECT_THROW(open_sim_camera(socket_), lightstage::camera::CameraError);
}

TEST(SimCamera, NobodyServingIsNotFound) {
  try {
    open_sim_camera((testing::socket_dir() / "nobody.sock").string());
    FAIL();
  } catch (const lightstage::camera::CameraError& e) {
    EXPECT_EQ(e.kind(), lightstage::camera::CameraError::Kind::kNotFound);
    EXPECT_NE(std::string(e.what()).find("nobody.sock"), std::string::npos);
  }
}

}  // namespace
}  // namespace lightstage::sim
