#include "lightstage/sim/camera/sim_camera.hpp"

#include "lightstage/common/message_channel.hpp"
#include "lightstage/common/socket_link.hpp"
#include "lightstage/proto/sim_camera.pb.h"

#include <fmt/format.h>

#include <cstring>
#include <deque>

namespace lightstage::sim {
namespace {

namespace pb = lightstage::proto::simcam;
using camera::CameraError;

constexpr auto kReplyTimeout = std::chrono::seconds(5);

class SimCamera final : public camera::Camera {
 public:
  SimCamera(const std::string& uri, std::unique_ptr<ByteLink> link) : Camera(uri), channel_(std::move(link)) {
    pb::ClientMessage get;
    get.mutable_get_info();
    const pb::ServerMessage reply = request(get);
    if (!reply.has_info()) throw CameraError(fmt::format("{}: the sim answered GetInfo without info", uri));
    info_ = reply.info();
    config_ = default_config();
  }

  ~SimCamera() override {
    try {
      stop();
    } catch (const Error&) {
    }
  }

  camera::CameraInfo info() const override { return {uri(), info_.model(), "lightstage-sim"}; }

  std::vector<camera::FormatInfo> formats() const override {
    camera::FormatInfo f;
    f.pixel_format = info_.pixel_format();
    f.bit_depth = static_cast<int>(info_.bit_depth());
    f.description = "simulated 16-bit linear sensor";
    const camera::Size size{static_cast<int>(info_.width()), static_cast<int>(info_.height())};
    f.sizes.push_back({size, size, 1, 1});
    return {f};
  }

  std::vector<camera::TriggerMode> trigger_modes() const override {
    return {camera::TriggerMode::kFreeRun, camera::TriggerMode::kSoftware, camera::TriggerMode::kHardware};
  }

  camera::CameraConfig default_config() const override {
    camera::CameraConfig c;
    c.pixel_format = info_.pixel_format();
    c.size = {static_cast<int>(info_.width()), static_cast<int>(info_.height())};
    return c;
  }

  camera::Validation validate(camera::CameraConfig& config) const override {
    camera::Validation v;
    const camera::CameraConfig d = default_config();
    const auto adjust = [&](const std::string& note) {
      v.notes.push_back(note);
      if (v.status == camera::ConfigStatus::kValid) v.status = camera::ConfigStatus::kAdjusted;
    };
    if (config.pixel_format.empty()) config.pixel_format = d.pixel_format;
    if (config.pixel_format != d.pixel_format) {
      adjust(fmt::format("pixel_format {} -> {} (the only one)", config.pixel_format, d.pixel_format));
      config.pixel_format = d.pixel_format;
    }
    if (config.size.width == 0 && config.size.height == 0) config.size = d.size;
    if (!(config.size == d.size)) {
      adjust(fmt::format("size {}x{} -> {}x{} (fixed)", config.size.width, config.size.height, d.size.width,
                         d.size.height));
      config.size = d.size;
    }
    if (config.roi) {
      const auto& r = *config.roi;
      if (r.x < 0 || r.y < 0 || r.width <= 0 || r.height <= 0 || r.x + r.width > d.size.width ||
          r.y + r.height > d.size.height) {
        v.notes.push_back(fmt::format("roi {}x{}+{}+{} is outside the {}x{} frame", r.width, r.height, r.x,
                                      r.y, d.size.width, d.size.height));
        v.status = camera::ConfigStatus::kInvalid;
      }
    }
    return v;
  }

  void configure(const camera::CameraConfig& config) override {
    camera::CameraConfig checked = config;
    const camera::Validation v = validate(checked);
    if (v.status != camera::ConfigStatus::kValid) {
      throw CameraError(fmt::format("{}: configuration not valid: {}", uri(), v.message()));
    }
    pb::ClientMessage m;
    auto* c = m.mutable_configure();
    c->set_trigger(config.trigger == camera::TriggerMode::kHardware   ? pb::HARDWARE
                   : config.trigger == camera::TriggerMode::kSoftware ? pb::SOFTWARE
                                                                      : pb::FREE_RUN);
    if (config.roi) {
      c->set_roi_x(static_cast<std::uint32_t>(config.roi->x));
      c->set_roi_y(static_cast<std::uint32_t>(config.roi->y));
      c->set_roi_width(static_cast<std::uint32_t>(config.roi->width));
      c->set_roi_height(static_cast<std::uint32_t>(config.roi->height));
    }
    request(m);
    config_ = checked;
  }

  camera::CameraConfig configuration() const override { return config_; }

  camera::ControlInfo control_info() const override {
    camera::ControlInfo c;
    c.exposure_min_us = info_.exposure_min_us();
    c.exposure_max_us = info_.exposure_max_us();
    c.gain_min = info_.gain_min();
    c.gain_max = info_.gain_max();
    c.latency_frames = 0;  // every frame reports the exposure and gain it was taken with
    return c;
  }

  camera::Controls set_controls(const camera::Controls& controls) override {
    const camera::ControlInfo range = control_info();
    if (controls.exposure_us &&
        !(*controls.exposure_us >= range.exposure_min_us && *controls.exposure_us <= range.exposure_max_us)) {
      throw CameraError(fmt::format("{}: exposure {} us is outside [{}, {}] us", uri(), *controls.exposure_us,
                                    range.exposure_min_us, range.exposure_max_us));
    }
    if (controls.analogue_gain &&
        !(*controls.analogue_gain >= range.gain_min && *controls.analogue_gain <= range.gain_max)) {
      throw CameraError(fmt::format("{}: analogue gain {} is outside [{}, {}]", uri(),
                                    *controls.analogue_gain, range.gain_min, range.gain_max));
    }
    pb::ClientMessage m;
    m.mutable_set_controls()->set_exposure_us(controls.exposure_us.value_or(0));
    m.mutable_set_controls()->set_analogue_gain(controls.analogue_gain.value_or(0));
    const pb::ServerMessage reply = request(m);
    info_.set_exposure_us(reply.info().exposure_us());
    info_.set_analogue_gain(reply.info().analogue_gain());
    return {info_.exposure_us(), info_.analogue_gain()};
  }

  void start() override {
    pb::ClientMessage m;
    m.mutable_start();
    request(m);
    streaming_ = true;
  }

  void stop() override {
    if (!streaming_) return;
    pb::ClientMessage m;
    m.mutable_stop();
    streaming_ = false;
    request(m);
    frames_.clear();
  }

  bool streaming() const override { return streaming_; }

  void trigger() override {
    if (config_.trigger != camera::TriggerMode::kSoftware) {
      throw CameraError(camera::CameraError::Kind::kUnsupported,
                        fmt::format("{}: trigger() needs software trigger mode", uri()));
    }
    pb::ClientMessage m;
    m.mutable_software_trigger();
    request(m);
  }

  std::optional<camera::Frame> wait_frame(std::chrono::milliseconds timeout) override {
    if (!streaming_) throw CameraError(fmt::format("{}: wait_frame while not streaming", uri()));
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (frames_.empty()) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return std::nullopt;
      pb::ServerMessage m;
      if (!receive(m, left)) return std::nullopt;
      take(std::move(m));
    }
    camera::Frame f = to_frame(frames_.front());
    frames_.pop_front();
    return f;
  }

 private:
  bool receive(pb::ServerMessage& m, std::chrono::milliseconds timeout) {
    try {
      return channel_.receive(m, timeout);
    } catch (const LinkClosed& e) {
      streaming_ = false;
      throw CameraError(camera::CameraError::Kind::kDisconnected, fmt::format("{}: {}", uri(), e.what()));
    } catch (const ProtocolError& e) {
      throw CameraError(fmt::format("{}: {}", uri(), e.what()));
    }
  }

  // Frames arriving while waiting for a reply are kept for wait_frame.
  void take(pb::ServerMessage&& m) {
    if (m.has_frame()) {
      if (streaming_) frames_.push_back(std::move(*m.mutable_frame()));
    } else if (m.has_error() && m.request_id() == 0) {
      throw CameraError(fmt::format("{}: {}", uri(), m.error().message()));
    }
  }

  pb::ServerMessage request(pb::ClientMessage m) {
    m.set_request_id(next_id_++);
    try {
      channel_.send(m);
    } catch (const LinkClosed& e) {
      throw CameraError(camera::CameraError::Kind::kDisconnected, fmt::format("{}: {}", uri(), e.what()));
    }
    const auto deadline = std::chrono::steady_clock::now() + kReplyTimeout;
    for (;;) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      pb::ServerMessage reply;
      if (left.count() <= 0 || !receive(reply, left)) {
        throw CameraError(camera::CameraError::Kind::kTimeout,
                          fmt::format("{}: no reply from the sim", uri()));
      }
      if (reply.request_id() != m.request_id()) {
        take(std::move(reply));
        continue;
      }
      if (reply.has_error()) throw CameraError(fmt::format("{}: {}", uri(), reply.error().message()));
      return reply;
    }
  }

  camera::Frame to_frame(const pb::Frame& f) const {
    camera::Frame frame;
    const auto rows = static_cast<int>(f.height()), cols = static_cast<int>(f.width());
    if (f.pixels().size() != static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols) * 2) {
      throw CameraError(fmt::format("{}: frame {} carries {} bytes for {}x{} pixels", uri(), f.sequence(),
                                    f.pixels().size(), cols, rows));
    }
    frame.image = cv::Mat(rows, cols, CV_16UC1);
    std::memcpy(frame.image.data, f.pixels().data(), f.pixels().size());
    frame.pixel_format = info_.pixel_format();
    frame.bit_depth = static_cast<int>(f.bit_depth());
    frame.sequence = f.sequence();
    frame.timestamp_ns = f.timestamp_ns();
    frame.clock = camera::ClockDomain::kMonotonic;
    frame.timestamp_point = camera::TimestampPoint::kStartOfExposure;
    frame.exposure_us = f.exposure_us();
    frame.analogue_gain = f.analogue_gain();
    frame.controls_reported = true;
    return frame;
  }

  MessageChannel channel_;
  pb::Info info_;
  camera::CameraConfig config_;
  bool streaming_ = false;
  std::uint32_t next_id_ = 1;
  std::deque<pb::Frame> frames_;
};

}  // namespace

std::unique_ptr<camera::Camera> open_sim_camera(const std::string& socket_path) {
  const std::string uri = "sim:" + socket_path;
  std::unique_ptr<ByteLink> link;
  try {
    link = connect_socket_link("unix:" + socket_path, std::chrono::milliseconds(2000));
  } catch (const LinkClosed& e) {
    throw camera::CameraError(
        camera::CameraError::Kind::kNotFound,
        fmt::format("{}: no virtual camera there (is lightstage-sim running with --camera?): {}", uri,
                    e.what()));
  }
  return std::make_unique<SimCamera>(uri, std::move(link));
}

void register_sim_camera() {
  camera::CameraScheme scheme;
  scheme.scheme = "sim";
  scheme.form = "sim:/path/to/camera.sock";
  scheme.open = [](const camera::CameraUri& uri) { return open_sim_camera(uri.target); };
  camera::register_camera_scheme(std::move(scheme));
}

}  // namespace lightstage::sim
