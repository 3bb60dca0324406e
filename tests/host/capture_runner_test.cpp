// The capture runner against a scripted controller and camera in this process
// (software trigger: the controller lights the LED, the camera is triggered).
#include "lightstage/host/capture/capture_runner.hpp"

#include "lightstage/common/message_channel.hpp"
#include "lightstage/common/socket_link.hpp"
#include "lightstage/testing/errors.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <deque>
#include <mutex>
#include <thread>

namespace lightstage {
namespace {

using std::chrono::milliseconds;

// What the fake controller lit, for the fake camera to render.
struct Dome {
  std::atomic<int> lit{-1};  // -1: dark
};

// Answers Hello with Info (no strobe input, `max_steps` per sequence) and SetLeds with Ack.
class FakeController {
 public:
  FakeController(std::unique_ptr<ByteLink> link, Dome& dome, std::uint32_t max_steps)
      : channel_(std::move(link)) {
    thread_ = std::thread([this, &dome, max_steps] {
      try {
        for (;;) {
          proto::HostMessage m;
          if (!channel_.receive(m, milliseconds(20))) {
            if (stop_) return;
            continue;
          }
          if (m.has_heartbeat()) continue;
          proto::ControllerMessage reply;
          reply.set_request_id(m.request_id());
          if (m.has_hello()) {
            proto::Info* info = reply.mutable_info();
            info->set_protocol_version(1);
            info->set_rig_name("runner-test");
            info->mutable_capabilities()->set_max_sequence_steps(max_steps);
          } else if (m.has_set_leds()) {
            dome.lit = m.set_leds().leds().empty() ? -1 : static_cast<int>(m.set_leds().leds(0).led_id());
            reply.mutable_ack();
          } else {
            reply.mutable_error()->set_message("not scripted");
          }
          channel_.send(reply);
        }
      } catch (const LinkClosed&) {
      }
    });
  }
  ~FakeController() {
    stop_ = true;
    thread_.join();
  }

 private:
  MessageChannel channel_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// A software-triggered camera whose frames are filled with the lit LED's id
// (0 when dark); the triggers listed in `drop` give no frame.
class FakeCamera final : public camera::Camera {
 public:
  explicit FakeCamera(Dome& dome) : Camera("fake:cam"), dome_(dome) {}
  camera::CameraInfo info() const override { return {uri(), "fake", "test"}; }
  std::vector<camera::FormatInfo> formats() const override { return {}; }
  std::vector<camera::TriggerMode> trigger_modes() const override { return {camera::TriggerMode::kSoftware}; }
  camera::CameraConfig default_config() const override { return {}; }
  camera::Validation validate(camera::CameraConfig&) const override { return {}; }
  void configure(const camera::CameraConfig& config) override { trigger_mode = config.trigger; }
  camera::CameraConfig configuration() const override { return {}; }
  camera::ControlInfo control_info() const override { return {}; }
  camera::Controls set_controls(const camera::Controls& c) override {
    if (c.exposure_us) exposure_us = *c.exposure_us;
    return {exposure_us, c.analogue_gain.value_or(1.5)};
  }
  void start() override { streaming_ = true; }
  void stop() override { streaming_ = false; }
  bool streaming() const override { return streaming_; }
  void trigger() override {
    const int n = triggers++;
    shots.emplace_back(dome_.lit.load(), exposure_us);
    if (drop_all || std::ranges::count(drop, n) > 0) return;
    camera::Frame frame;
    frame.bit_depth = 12;
    frame.sequence = static_cast<std::uint64_t>(n);
    frame.exposure_us = exposure_us;
    frame.image = cv::Mat(2, 3, CV_16UC1, cv::Scalar(std::max(dome_.lit.load(), 0)));
    ready_.push_back(std::move(frame));
  }
  std::optional<camera::Frame> wait_frame(milliseconds) override {
    if (ready_.empty()) return std::nullopt;
    camera::Frame frame = std::move(ready_.front());
    ready_.pop_front();
    return frame;
  }

  camera::TriggerMode trigger_mode = camera::TriggerMode::kFreeRun;
  double exposure_us = 0;
  int triggers = 0;
  std::vector<int> drop;
  bool drop_all = false;
  std::vector<std::pair<int, double>> shots;  // (lit LED, exposure) at each trigger

 private:
  Dome& dome_;
  bool streaming_ = false;
  std::deque<camera::Frame> ready_;
};

struct Bench {
  explicit Bench(std::uint32_t max_steps = 12) {
    auto [host_end, controller_end] = socket_link_pair();
    controller = std::make_unique<FakeController>(std::move(controller_end), dome, max_steps);
    client = std::make_unique<ControllerClient>(std::move(host_end));
  }
  Dome dome;
  std::unique_ptr<FakeController> controller;
  std::unique_ptr<ControllerClient> client;
  FakeCamera cam{dome};
};

int value_of(const Taken& taken) { return taken.frame.image.at<std::uint16_t>(0, 0); }

TEST(CaptureRunner, ResolvesLoopAndTriggerAndStartsTheCameraForIt) {
  Bench bench;
  CaptureOptions options;
  options.gain = 1.5;
  CaptureRunner runner(*bench.client, bench.cam, options);
  EXPECT_FALSE(runner.closed_loop());  // auto, and no strobe input
  EXPECT_FALSE(runner.hardware_trigger());
  runner.start();
  EXPECT_EQ(bench.cam.trigger_mode, camera::TriggerMode::kSoftware);
  EXPECT_TRUE(bench.cam.streaming());
  EXPECT_DOUBLE_EQ(runner.gain(), 1.5);
  runner.stop();
  EXPECT_FALSE(bench.cam.streaming());

  options.loop = "closed";
  EXPECT_NE(testing::error_of([&] {
              CaptureRunner closed(*bench.client, bench.cam, options);
            }).find("no strobe input"),
            std::string::npos);
}

TEST(CaptureRunner, ADroppedFrameIsRetakenAndLandsAtItsShot) {
  Bench bench;
  bench.cam.drop = {1};
  CaptureOptions options;
  CaptureRunner runner(*bench.client, bench.cam, options);
  runner.start();
  const Batch batch = runner.run_batch({{4, 1000}, {5, 1000}, {6, 1000}});
  ASSERT_EQ(batch.taken.size(), 3u);
  EXPECT_EQ(batch.retakes, 1u);
  EXPECT_EQ(value_of(batch.taken.at(0)), 4);
  EXPECT_EQ(value_of(batch.taken.at(1)), 5);
  EXPECT_EQ(value_of(batch.taken.at(2)), 6);
  EXPECT_EQ(bench.cam.triggers, 4);
  EXPECT_EQ(bench.dome.lit, -1);  // dark again after each shot
}

TEST(CaptureRunner, AShotWithoutAFrameAfterItsRetakesIsAnErrorNamingTheCameraAndLed) {
  Bench bench;
  bench.cam.drop_all = true;
  CaptureOptions options;
  options.max_retakes = 2;
  CaptureRunner runner(*bench.client, bench.cam, options);
  runner.start();
  try {
    runner.run_batch({{5, 1000}});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    ADD_FAILURE() << "a device failure, not bad input: " << e.what();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "fake:cam: no frame for LED 5 after 2 retakes");
  }
  EXPECT_EQ(bench.cam.triggers, 3);
}

TEST(CaptureRunner, SingleExposuresAreTakenExposureByExposureInPlanOrderSkippingDoneFrames) {
  Bench bench(/*max_steps=*/2);
  bench.cam.drop = {0};
  CaptureOptions options;
  CaptureRunner runner(*bench.client, bench.cam, options);
  runner.start();
  const CapturePlan plan = make_plan({4, 5, 6, 7}, {{4, 2000}, {5, 500}, {6, 2000}, {7, 2000}}, {}, {}, 0);
  std::vector<std::pair<std::size_t, int>> handed;  // (frame, LED lit in its image)
  runner.take_frames(plan, {false, false, true, false}, [&](std::size_t frame, std::vector<Take>& takes) {
    ASSERT_EQ(takes.size(), 1u);
    EXPECT_EQ(takes[0].exposure, plan.frames[frame].exposure);
    handed.emplace_back(frame, value_of(takes[0].taken));
  });
  EXPECT_EQ(handed, (std::vector<std::pair<std::size_t, int>>{{1, 5}, {0, 4}, {3, 7}}));
  EXPECT_EQ(bench.cam.shots, (std::vector<std::pair<int, double>>{{5, 500}, {5, 500}, {4, 2000}, {7, 2000}}));
  EXPECT_EQ(runner.stats().retakes, 1u);
}

TEST(CaptureRunner, BracketsAreTakenGroupByGroupEachAtItsExposuresShortestFirst) {
  Bench bench(/*max_steps=*/2);
  CaptureOptions options;
  CaptureRunner runner(*bench.client, bench.cam, options);
  runner.start();
  const CapturePlan plan = make_plan({4, 5, 6}, {{4, 1000}, {5, 1000}, {6, 1000}},
                                     {{4, {125, 1000}}, {5, {125, 1000}}, {6, {250, 1000}}}, {-3, 0}, 0);
  std::vector<std::size_t> handed;
  runner.take_frames(plan, {}, [&](std::size_t frame, std::vector<Take>& takes) {
    handed.push_back(frame);
    ASSERT_EQ(takes.size(), 2u);
    EXPECT_EQ(takes[0].exposure, plan.frames[frame].bracket[0]);
    EXPECT_EQ(takes[1].exposure, plan.frames[frame].bracket[1]);
    for (const Take& take : takes) EXPECT_EQ(value_of(take.taken), plan.frames[frame].led_id);
  });
  EXPECT_EQ(handed, (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(bench.cam.shots, (std::vector<std::pair<int, double>>{
                                 {4, 125}, {5, 125}, {4, 1000}, {5, 1000}, {6, 250}, {6, 1000}}));
}

}  // namespace
}  // namespace lightstage
