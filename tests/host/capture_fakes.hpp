#pragma once
// A scripted controller and camera in this process, for the capture's runner
// and session tests. Software trigger: the controller lights the LED, the
// camera is triggered and fills its frame with the lit LED's id. Hardware
// trigger: the controller runs sequences whose steps expose such frames.

#include "lightstage/common/camera.hpp"
#include "lightstage/common/message_channel.hpp"
#include "lightstage/common/socket_link.hpp"
#include "lightstage/host/controller/controller_client.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <atomic>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace lightstage::testing {

using std::chrono::milliseconds;

// What the fake controller lit, for the fake camera to render.
struct Dome {
  std::atomic<int> lit{-1};  // -1: dark
  // Hardware trigger: frames the controller's sequences exposed, for the camera to deliver.
  std::mutex mutex;
  std::deque<camera::Frame> exposed;
  // The sequence (counted from 0) the controller's watchdog ends, after how many steps.
  int watchdog_sequence = -1;
  std::size_t watchdog_after = 0;
  int sequences_run = 0;
  std::vector<proto::Sequence> uploaded;  // every sequence the host sent, in order (guarded by mutex)
};

// Runs `sequence` as a controller would, without time passing: each step
// triggers one frame (stamped 100 us after its trigger, the lit LED's id in
// every pixel) until the watchdog cuts a step short.
inline void run_fake_sequence(const proto::Sequence& sequence, Dome& dome, MessageChannel& channel) {
  constexpr std::int64_t kStepNs = 100'000'000;  // apart more than the matcher's trigger latency
  const std::int64_t start_ns = 1'000'000'000;
  std::uint32_t run = 0;
  proto::Outcome outcome = proto::OK;
  const bool watchdog = dome.sequences_run++ == dome.watchdog_sequence;
  for (int k = 0; k < sequence.steps_size(); ++k) {
    const proto::Step& step = sequence.steps(k);
    proto::ControllerMessage event;
    proto::StepEvent* e = event.mutable_step_event();
    e->set_sequence_id(sequence.id());
    e->set_step(static_cast<std::uint32_t>(k));
    e->set_tag(step.tag());
    e->set_trigger_ns(start_ns + k * kStepNs);
    if (watchdog && static_cast<std::size_t>(k) >= dome.watchdog_after) {
      outcome = proto::WATCHDOG;
      e->set_outcome(outcome);
      channel.send(event);
      break;
    }
    camera::Frame frame;
    frame.bit_depth = 12;
    frame.sequence = static_cast<std::uint64_t>(k);
    frame.timestamp_ns = e->trigger_ns() + 100'000;
    frame.timestamp_point = camera::TimestampPoint::kStartOfExposure;
    frame.image = cv::Mat(2, 3, CV_16UC1, cv::Scalar(step.leds().empty() ? 0 : step.leds(0).led_id()));
    {
      const std::lock_guard lock(dome.mutex);
      dome.exposed.push_back(std::move(frame));
    }
    e->set_outcome(proto::OK);
    channel.send(event);
    ++run;
  }
  proto::ControllerMessage done;
  done.mutable_sequence_done()->set_sequence_id(sequence.id());
  done.mutable_sequence_done()->set_steps_run(run);
  done.mutable_sequence_done()->set_outcome(outcome);
  if (outcome != proto::OK) done.mutable_sequence_done()->set_detail("heartbeats stopped");
  channel.send(done);
}

// Answers Hello with Info (`max_steps` per sequence, `leds` with their limits,
// a strobe input when `strobe`), SetLeds with Ack, UploadSequence and
// RunSequence by running it (run_fake_sequence).
class FakeController {
 public:
  FakeController(std::unique_ptr<ByteLink> link, Dome& dome, std::uint32_t max_steps,
                 std::vector<proto::Led> leds = {}, bool strobe = false)
      : channel_(std::move(link)) {
    thread_ = std::thread([this, &dome, max_steps, leds = std::move(leds), strobe] {
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
            info->mutable_capabilities()->set_strobe_input(strobe);
            for (const proto::Led& led : leds) *info->add_leds() = led;
          } else if (m.has_set_leds()) {
            dome.lit = m.set_leds().leds().empty() ? -1 : static_cast<int>(m.set_leds().leds(0).led_id());
            reply.mutable_ack();
          } else if (m.has_upload()) {
            uploaded_ = m.upload().sequence();
            const std::lock_guard lock(dome.mutex);
            dome.uploaded.push_back(uploaded_);
            reply.mutable_ack();
          } else if (m.has_run()) {
            reply.mutable_ack();
          } else {
            reply.mutable_error()->set_message("not scripted");
          }
          channel_.send(reply);
          if (m.has_run()) run_fake_sequence(uploaded_, dome, channel_);
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
  proto::Sequence uploaded_;
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
  std::vector<camera::TriggerMode> trigger_modes() const override {
    if (hardware) return {camera::TriggerMode::kHardware, camera::TriggerMode::kSoftware};
    return {camera::TriggerMode::kSoftware};
  }
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
    if (hardware) {
      {
        const std::lock_guard lock(dome_.mutex);
        if (!dome_.exposed.empty()) {
          camera::Frame frame = std::move(dome_.exposed.front());
          dome_.exposed.pop_front();
          return frame;
        }
      }
      std::this_thread::sleep_for(milliseconds(1));
      return std::nullopt;
    }
    if (ready_.empty()) return std::nullopt;
    camera::Frame frame = std::move(ready_.front());
    ready_.pop_front();
    return frame;
  }

  bool hardware = false;  // frames come from the controller's sequences (Dome::exposed)
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
  explicit Bench(std::uint32_t max_steps = 12, std::vector<proto::Led> leds = {}, bool strobe = false) {
    auto [host_end, controller_end] = socket_link_pair();
    controller =
        std::make_unique<FakeController>(std::move(controller_end), dome, max_steps, std::move(leds), strobe);
    client = std::make_unique<ControllerClient>(std::move(host_end));
  }
  Dome dome;
  std::unique_ptr<FakeController> controller;
  std::unique_ptr<ControllerClient> client;
  FakeCamera cam{dome};
};

}  // namespace lightstage::testing
