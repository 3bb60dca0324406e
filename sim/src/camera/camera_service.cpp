#include "lightstage/sim/camera/camera_service.hpp"

#include "lightstage/common/clock.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/message_channel.hpp"
#include "lightstage/proto/sim_camera.pb.h"

#include <fmt/format.h>

#include <chrono>

namespace lightstage::sim {
namespace {

namespace pb = lightstage::proto::simcam;

constexpr double kMinExposureUs = 10, kMaxExposureUs = 10'000'000;
constexpr double kMinGain = 0.1, kMaxGain = 16;

}  // namespace

CameraService::CameraService(std::shared_ptr<const World> world, SensorOptions sensor,
                             CameraServiceOptions options)
    : world_(std::move(world)), sensor_options_(std::move(sensor)), options_(std::move(options)) {
  const Rig& rig = world_->rig();
  for (std::size_t i = 0; i < rig.leds.size(); ++i) led_index_[rig.leds[i].id] = i;
  exposure_us_ = world_->sensor().exposure_us();
  gain_ = world_->sensor().gain();
  tracker_ =
      std::make_shared<ExposureTracker>(options_.trigger_line, [this](std::int64_t t) { on_trigger(t); });
  worker_ = std::jthread([this](std::stop_token stop) { run_exposures(stop); });
}

CameraService::~CameraService() {
  worker_.request_stop();
  changed_.notify_all();
}

std::uint64_t CameraService::frames_sent() const {
  const std::lock_guard lock(mutex_);
  return sequence_;
}

void CameraService::on_trigger(std::int64_t t_ns) {
  const std::lock_guard lock(mutex_);
  if (!streaming_ || mode_ != Mode::kHardware) return;
  queue_exposure(t_ns + options_.trigger_delay_ns);
}

// Caller holds mutex_.
void CameraService::queue_exposure(std::int64_t start_ns) {
  if (start_ns < busy_until_ns_) return;  // still exposing: a real sensor ignores the trigger
  const auto length = static_cast<std::int64_t>(exposure_us_ * 1000);
  pending_.push_back({start_ns, start_ns + length});
  busy_until_ns_ = start_ns + length;
  changed_.notify_all();
}

void CameraService::run_exposures(std::stop_token stop) {
  while (!stop.stop_requested()) {
    Exposure exposure{};
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, stop,
                    [this] { return !pending_.empty() || (streaming_ && mode_ == Mode::kFreeRun); });
      if (stop.stop_requested()) return;
      if (pending_.empty()) queue_exposure(std::max(monotonic_now_ns(), busy_until_ns_));
      exposure = pending_.front();
      pending_.pop_front();
      // Wait for the window to pass and for the chip to catch up with it.
      changed_.wait_until(lock, stop, steady_at(exposure.end_ns + kWindowSettleNs), [] { return false; });
      while (!stop.stop_requested() && tracker_->latest_ns() < exposure.end_ns &&
             monotonic_now_ns() < exposure.end_ns + kWindowCatchUpNs) {
        changed_.wait_for(lock, stop, std::chrono::milliseconds(1), [] { return false; });
      }
      if (stop.stop_requested()) return;
      if (!streaming_) continue;  // stopped while waiting: the frame is not wanted
    }
    deliver(exposure);
    tracker_->forget_before(exposure.start_ns - 1'000'000'000);
  }
}

void CameraService::deliver(const Exposure& exposure) {
  std::vector<std::pair<std::size_t, double>> leds;
  pb::ServerMessage message;
  pb::Frame* frame = message.mutable_frame();
  for (const auto& [id, share] : tracker_->lit_shares(exposure.start_ns, exposure.end_ns)) {
    const auto it = led_index_.find(id);
    if (it == led_index_.end()) continue;
    leds.emplace_back(it->second, share);
    frame->add_led_ids(static_cast<std::uint32_t>(id));
    frame->add_led_weights(share);
  }
  std::shared_ptr<MessageChannel> client;
  SensorOptions sensor_options = sensor_options_;
  std::uint64_t sequence = 0;
  int rx = 0, ry = 0, rw = 0, rh = 0;
  {
    const std::lock_guard lock(mutex_);
    client = client_;
    sensor_options.exposure_us = exposure_us_;
    sensor_options.gain = gain_;
    sequence = sequence_++;
    rx = roi_x_, ry = roi_y_, rw = roi_width_, rh = roi_height_;
  }
  if (!client) return;
  if (options_.drop_frames.contains(sequence + 1)) {
    logger("sim")->warn("camera fault drop-frame:{}: frame {} is lost", sequence + 1, sequence);
    return;
  }
  const Sensor sensor(sensor_options, world_->rig().camera);
  cv::Mat image = sensor.expose(world_->render(leds), options_.seed, sequence);
  if (rw > 0) image = image(cv::Rect(rx, ry, rw, rh)).clone();
  frame->set_sequence(sequence);
  frame->set_timestamp_ns(exposure.start_ns);
  frame->set_exposure_us(sensor.exposure_us());
  frame->set_analogue_gain(sensor.gain());
  frame->set_width(static_cast<std::uint32_t>(image.cols));
  frame->set_height(static_cast<std::uint32_t>(image.rows));
  frame->set_bit_depth(16);
  // Samples are little-endian uint16, as this x86/ARM host stores them.
  frame->set_pixels(image.ptr<char>(), image.total() * image.elemSize());
  try {
    client->send(message);
  } catch (const Error& e) {
    logger("sim")->warn("camera: frame {} not delivered: {}", sequence, e.what());
  }
}

void CameraService::serve(std::unique_ptr<ByteLink> link, std::stop_token stop) {
  const std::string peer = link->describe();
  auto channel = std::make_shared<MessageChannel>(std::move(link));
  {
    const std::lock_guard lock(mutex_);
    if (client_) {
      pb::ServerMessage busy;
      busy.mutable_error()->set_message("the virtual camera is in use by another client");
      try {
        channel->send(busy);
      } catch (const Error&) {
      }
      return;
    }
    client_ = channel;
  }
  logger("sim")->info("camera: client connected ({})", peer);
  const cv::Size size(world_->renderer().camera().width, world_->renderer().camera().height);
  try {
    while (!stop.stop_requested()) {
      pb::ClientMessage request;
      pb::ServerMessage reply;
      try {
        if (!channel->receive(request, std::chrono::milliseconds(100))) continue;
      } catch (const ProtocolError& e) {
        reply.mutable_error()->set_message(e.what());
        channel->send(reply);
        continue;
      }
      reply.set_request_id(request.request_id());
      std::function<void()> after_reply;
      {
        const std::lock_guard lock(mutex_);
        switch (request.body_case()) {
          case pb::ClientMessage::kGetInfo: {
            pb::Info* info = reply.mutable_info();
            info->set_model("lightstage-sim " + world_->scene().name);
            info->set_width(static_cast<std::uint32_t>(size.width));
            info->set_height(static_cast<std::uint32_t>(size.height));
            info->set_bit_depth(16);
            info->set_pixel_format("Y16");
            info->set_exposure_us(exposure_us_);
            info->set_analogue_gain(gain_);
            info->set_exposure_min_us(kMinExposureUs);
            info->set_exposure_max_us(kMaxExposureUs);
            info->set_gain_min(kMinGain);
            info->set_gain_max(kMaxGain);
            info->set_black_level(world_->sensor().black_level());
            info->set_saturation_level(world_->sensor().saturation_level());
            break;
          }
          case pb::ClientMessage::kConfigure: {
            const auto& c = request.configure();
            const bool roi = c.roi_width() > 0 || c.roi_height() > 0;
            if (streaming_) {
              reply.mutable_error()->set_message("configure: the camera is streaming; stop it first");
            } else if (roi && (c.roi_width() == 0 || c.roi_height() == 0 ||
                               c.roi_x() + c.roi_width() > static_cast<std::uint32_t>(size.width) ||
                               c.roi_y() + c.roi_height() > static_cast<std::uint32_t>(size.height))) {
              reply.mutable_error()->set_message(
                  fmt::format("configure: ROI {}x{}+{}+{} is outside the {}x{} frame", c.roi_width(),
                              c.roi_height(), c.roi_x(), c.roi_y(), size.width, size.height));
            } else {
              mode_ = c.trigger() == pb::FREE_RUN   ? Mode::kFreeRun
                      : c.trigger() == pb::SOFTWARE ? Mode::kSoftware
                                                    : Mode::kHardware;
              roi_x_ = static_cast<int>(c.roi_x());
              roi_y_ = static_cast<int>(c.roi_y());
              roi_width_ = static_cast<int>(c.roi_width());
              roi_height_ = static_cast<int>(c.roi_height());
              reply.mutable_ack();
            }
            break;
          }
          case pb::ClientMessage::kSetControls: {
            const auto& c = request.set_controls();
            if (c.exposure_us() != 0 &&
                !(c.exposure_us() >= kMinExposureUs && c.exposure_us() <= kMaxExposureUs)) {
              reply.mutable_error()->set_message(fmt::format(
                  "exposure_us {} is outside [{}, {}]", c.exposure_us(), kMinExposureUs, kMaxExposureUs));
            } else if (c.analogue_gain() != 0 &&
                       !(c.analogue_gain() >= kMinGain && c.analogue_gain() <= kMaxGain)) {
              reply.mutable_error()->set_message(
                  fmt::format("analogue_gain {} is outside [{}, {}]", c.analogue_gain(), kMinGain, kMaxGain));
            } else {
              if (c.exposure_us() != 0) exposure_us_ = c.exposure_us();
              if (c.analogue_gain() != 0) gain_ = c.analogue_gain();
              const auto exposure_ns = static_cast<std::int64_t>(exposure_us_ * 1000);
              if (options_.on_exposure_change)
                after_reply = [this, exposure_ns] { options_.on_exposure_change(exposure_ns); };
              reply.mutable_info()->set_exposure_us(exposure_us_);
              reply.mutable_info()->set_analogue_gain(gain_);
            }
            break;
          }
          case pb::ClientMessage::kStart:
            streaming_ = true;
            busy_until_ns_ = 0;
            changed_.notify_all();
            reply.mutable_ack();
            break;
          case pb::ClientMessage::kStop:
            streaming_ = false;
            pending_.clear();
            reply.mutable_ack();
            break;
          case pb::ClientMessage::kSoftwareTrigger:
            if (!streaming_ || mode_ != Mode::kSoftware) {
              reply.mutable_error()->set_message(
                  "software trigger: the camera is not streaming in software mode");
            } else {
              queue_exposure(monotonic_now_ns());
              reply.mutable_ack();
            }
            break;
          default:
            reply.mutable_error()->set_message("unknown request");
        }
      }
      if (after_reply) after_reply();
      channel->send(reply);
    }
  } catch (const LinkClosed&) {
  }
  const std::lock_guard lock(mutex_);
  streaming_ = false;
  pending_.clear();
  client_.reset();
  logger("sim")->info("camera: client left ({})", peer);
}

}  // namespace lightstage::sim
