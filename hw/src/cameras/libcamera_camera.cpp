// The libcamera:ID camera (libcamera 0.0.3, Debian 12): one raw stream
// (StreamRole::Raw), manual ExposureTime / AnalogueGain per request, frames
// stamped with the SensorTimestamp metadata (CLOCK_BOOTTIME as libcamera
// documents it) and the exposure and gain the pipeline reports as applied.
//
// libcamera completes requests on its own thread: requestCompleted only queues
// the request; wait_frame() copies the image out on the caller's thread and
// queues the request again.
#include "backend_common.hpp"
#include "libcamera_manager.hpp"
#include "lightstage/hw/cameras.hpp"
#include "lightstage/hw/pixel_formats.hpp"

#include <libcamera/camera.h>
#include <libcamera/control_ids.h>
#include <libcamera/formats.h>
#include <libcamera/framebuffer.h>
#include <libcamera/framebuffer_allocator.h>
#include <libcamera/property_ids.h>
#include <libcamera/request.h>
#include <libcamera/stream.h>
#include <sys/mman.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <mutex>
#include <stdexcept>
#include <vector>

namespace lightstage::hw {

namespace {

using camera::CameraError;
using Kind = camera::CameraError::Kind;

// libcamera's raw formats under our (V4L2) names.
struct FormatName {
  libcamera::PixelFormat format;
  std::string_view name;
};

const std::vector<FormatName>& format_names() {
  namespace f = libcamera::formats;
  static const std::vector<FormatName> names = {
      {f::R8, "GREY"},
      {f::R10, "Y10"},
      {f::R12, "Y12"},
      {f::R10_CSI2P, "Y10P"},
      {f::YUYV, "YUYV"},
      {f::SBGGR8, "SBGGR8"},
      {f::SGBRG8, "SGBRG8"},
      {f::SGRBG8, "SGRBG8"},
      {f::SRGGB8, "SRGGB8"},
      {f::SBGGR10, "SBGGR10"},
      {f::SGBRG10, "SGBRG10"},
      {f::SGRBG10, "SGRBG10"},
      {f::SRGGB10, "SRGGB10"},
      {f::SBGGR12, "SBGGR12"},
      {f::SGBRG12, "SGBRG12"},
      {f::SGRBG12, "SGRBG12"},
      {f::SRGGB12, "SRGGB12"},
      {f::SBGGR16, "SBGGR16"},
      {f::SGBRG16, "SGBRG16"},
      {f::SGRBG16, "SGRBG16"},
      {f::SRGGB16, "SRGGB16"},
      {f::SBGGR10_CSI2P, "SBGGR10P"},
      {f::SGBRG10_CSI2P, "SGBRG10P"},
      {f::SGRBG10_CSI2P, "SGRBG10P"},
      {f::SRGGB10_CSI2P, "SRGGB10P"},
      {f::SBGGR12_CSI2P, "SBGGR12P"},
      {f::SGBRG12_CSI2P, "SGBRG12P"},
      {f::SGRBG12_CSI2P, "SGRBG12P"},
      {f::SRGGB12_CSI2P, "SRGGB12P"},
  };
  return names;
}

const PixelFormatDesc* our_format(const libcamera::PixelFormat& format) {
  for (const auto& n : format_names()) {
    if (n.format == format) return find_pixel_format(n.name);
  }
  return nullptr;
}

std::optional<libcamera::PixelFormat> their_format(std::string_view name) {
  for (const auto& n : format_names()) {
    if (n.name == name) return n.format;
  }
  return std::nullopt;
}

std::string list_ids(const std::vector<std::string>& ids) {
  return list_camera_uris(
      "libcamera", ids,
      "libcamera sees no camera (is the sensor's device-tree overlay loaded, and for most "
      "sensors the IPA package libcamera-ipa installed? see hw/docs/cameras.md)");
}

// One mapped plane of a FrameBuffer (dma-buf).
struct Mapping {
  void* base = nullptr;
  std::size_t length = 0;
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};

class LibcameraCamera final : public camera::Camera {
 public:
  LibcameraCamera(const camera::CameraUri& uri, std::shared_ptr<libcamera::CameraManager> manager)
      : Camera(uri.uri), manager_(std::move(manager)) {
    if (!uri.options.empty()) fail("camera URI '{}': libcamera: takes no options", uri.uri);
    const std::vector<std::string> ids = libcamera_camera_ids(*manager_);
    std::string id = uri.target;
    if (id.empty()) {
      if (ids.empty())
        throw CameraError(Kind::kNotFound, fmt::format("{}: no camera: {}", uri.uri, list_ids(ids)));
      id = ids.front();
    }
    camera_ = manager_->get(id);
    if (!camera_) {
      throw CameraError(Kind::kNotFound,
                        fmt::format("{}: no camera with id '{}'; {}", uri.uri, id, list_ids(ids)));
    }
    if (const int ret = camera_->acquire(); ret != 0) {
      camera_.reset();
      throw CameraError(ret == -EBUSY ? Kind::kBusy : Kind::kFailed,
                        fmt::format("{}: cannot acquire the camera: {}", uri.uri, std::strerror(-ret)));
    }
    id_ = id;
    model_ = camera_->properties().get(libcamera::properties::Model).value_or(id);
    camera_->requestCompleted.connect(this, &LibcameraCamera::request_completed);
    camera_->disconnected.connect(this, &LibcameraCamera::camera_disconnected);
    query_formats();
    initial_config_ = config_;
  }

  ~LibcameraCamera() override {
    try {
      stop();
    } catch (const std::exception&) {
      // Going away regardless.
    }
    release_buffers();
    camera_->requestCompleted.disconnect(this);
    camera_->disconnected.disconnect(this);
    camera_->release();
    camera_.reset();
  }

  camera::CameraInfo info() const override {
    return {uri(), model_, "libcamera " + libcamera::CameraManager::version()};
  }
  std::vector<camera::FormatInfo> formats() const override { return formats_; }
  std::vector<camera::TriggerMode> trigger_modes() const override {
    return {camera::TriggerMode::kFreeRun, camera::TriggerMode::kSoftware, camera::TriggerMode::kHardware};
  }
  camera::CameraConfig default_config() const override { return initial_config_; }
  camera::CameraConfig configuration() const override { return config_; }

  camera::Validation validate(camera::CameraConfig& config) const override {
    camera::Validation v;
    make_configuration(config, v);  // the libcamera configuration itself is not kept
    return v;
  }

  void configure(const camera::CameraConfig& requested) override {
    if (streaming_)
      throw CameraError(fmt::format("{}: cannot configure while streaming; stop() first", uri()));
    camera::CameraConfig config = requested;
    camera::Validation v;
    std::unique_ptr<libcamera::CameraConfiguration> lc = make_configuration(config, v);
    require_valid(v, uri());  // make_configuration() notes a refusal whenever it returns nullptr
    release_buffers();
    if (const int ret = camera_->configure(lc.get()); ret != 0) fail_ret("configure", ret);
    configuration_ = std::move(lc);
    stream_ = configuration_->at(0).stream();
    allocator_ = std::make_unique<libcamera::FrameBufferAllocator>(camera_);
    if (const int ret = allocator_->allocate(stream_); ret < 0) fail_ret("allocate buffers", ret);
    for (const auto& buffer : allocator_->buffers(stream_)) {
      const libcamera::FrameBuffer::Plane& plane = buffer->planes().front();
      const std::size_t length = plane.offset + plane.length;
      void* base = mmap(nullptr, length, PROT_READ, MAP_SHARED, plane.fd.get(), 0);
      if (base == MAP_FAILED) {
        const int err = errno;
        release_buffers();
        throw CameraError(fmt::format("{}: cannot map a frame buffer: {}", uri(), std::strerror(err)));
      }
      mappings_.push_back(
          {base, length, static_cast<const std::uint8_t*>(base) + plane.offset, plane.length});
      std::unique_ptr<libcamera::Request> request = camera_->createRequest(requests_.size());
      if (!request) {
        release_buffers();
        throw CameraError(fmt::format("{}: cannot create a request", uri()));
      }
      if (const int ret = request->addBuffer(stream_, buffer.get()); ret != 0) {
        release_buffers();
        fail_ret("add a buffer to a request", ret);
      }
      requests_.push_back(std::move(request));
    }
    format_ = our_format(configuration_->at(0).pixelFormat);
    stride_ = configuration_->at(0).stride;
    config_ = config;
  }

  camera::ControlInfo control_info() const override {
    camera::ControlInfo info;
    const libcamera::ControlInfoMap& map = camera_->controls();
    if (auto it = map.find(libcamera::controls::ExposureTime.id()); it != map.end()) {
      info.exposure_min_us = it->second.min().get<std::int32_t>();
      info.exposure_max_us = it->second.max().get<std::int32_t>();
      info.exposure_step_us = 1;
    }
    if (auto it = map.find(libcamera::controls::AnalogueGain.id()); it != map.end()) {
      info.gain_min = it->second.min().get<float>();
      info.gain_max = it->second.max().get<float>();
    }
    info.latency_frames = 0;  // frames report what was applied
    return info;
  }

  camera::Controls set_controls(const camera::Controls& controls) override {
    const libcamera::ControlInfoMap& map = camera_->controls();
    std::lock_guard lock(mutex_);
    if (controls.exposure_us) {
      const auto it = map.find(libcamera::controls::ExposureTime.id());
      if (it == map.end()) {
        throw CameraError(
            Kind::kUnsupported,
            fmt::format("{}: the camera offers no ExposureTime control (without the IPA package "
                        "libcamera-ipa a sensor has no exposure control; see hw/docs/cameras.md)",
                        uri()));
      }
      const double lo = it->second.min().get<std::int32_t>();
      const double hi = it->second.max().get<std::int32_t>();
      const double us = std::round(*controls.exposure_us);
      if (!std::isfinite(us) || us < lo || us > hi) {
        throw CameraError(fmt::format("{}: exposure_us {} is outside the camera's range [{}, {}]", uri(),
                                      *controls.exposure_us, lo, hi));
      }
      pending_exposure_us_ = static_cast<std::int32_t>(us);
      exposure_us_ = us;
    }
    if (controls.analogue_gain) {
      const auto it = map.find(libcamera::controls::AnalogueGain.id());
      if (it == map.end()) {
        throw CameraError(
            Kind::kUnsupported,
            fmt::format("{}: the camera offers no AnalogueGain control (is libcamera-ipa installed?)",
                        uri()));
      }
      const double lo = it->second.min().get<float>();
      const double hi = it->second.max().get<float>();
      const double gain = *controls.analogue_gain;
      if (!std::isfinite(gain) || gain < lo || gain > hi) {
        throw CameraError(
            fmt::format("{}: analogue_gain {} is outside the camera's range [{}, {}]", uri(), gain, lo, hi));
      }
      pending_gain_ = static_cast<float>(gain);
      gain_ = gain;
    }
    return {exposure_us_, gain_};
  }

  void start() override {
    if (streaming_) return;
    if (requests_.empty()) {  // never configured: the camera's own choice, as validated
      camera::CameraConfig config = config_;
      validate(config);
      configure(config);
    }
    libcamera::ControlList controls(camera_->controls());
    {
      std::lock_guard lock(mutex_);
      add_controls(controls);
      completed_.clear();
      disconnected_ = false;
    }
    if (const int ret = camera_->start(&controls); ret != 0) fail_ret("start", ret);
    streaming_ = true;
    have_last_sequence_ = false;
    trigger_pending_ = false;
    for (auto& request : requests_) {
      if (const int ret = camera_->queueRequest(request.get()); ret != 0) {
        stop();
        fail_ret("queue a request", ret);
      }
    }
  }

  void stop() override {
    if (!streaming_) return;
    streaming_ = false;
    const int ret = camera_->stop();  // cancels what is queued; returns once every request is back
    {
      std::lock_guard lock(mutex_);
      completed_.clear();
    }
    for (auto& request : requests_) request->reuse(libcamera::Request::ReuseBuffers);
    if (ret != 0 && ret != -ENODEV) fail_ret("stop", ret);
  }

  bool streaming() const override { return streaming_; }

  void trigger() override {
    check_software_trigger(config_, streaming_, uri());
    trigger_pending_ = true;
    trigger_boottime_ns_ = camera::clock_now_ns(camera::ClockDomain::kBoottime);
    trigger_monotonic_ns_ = camera::clock_now_ns(camera::ClockDomain::kMonotonic);
  }

  std::optional<camera::Frame> wait_frame(std::chrono::milliseconds timeout) override {
    if (!streaming_)
      throw CameraError(fmt::format("{}: wait_frame() while not streaming; start() first", uri()));
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      libcamera::Request* request = nullptr;
      {
        std::unique_lock lock(mutex_);
        if (!ready_.wait_until(lock, deadline, [&] { return disconnected_ || !completed_.empty(); })) {
          return std::nullopt;
        }
        if (disconnected_) {
          streaming_ = false;
          throw CameraError(Kind::kDisconnected, fmt::format("{}: camera disconnected", uri()));
        }
        request = completed_.front();
        completed_.pop_front();
      }
      std::optional<camera::Frame> frame = take_frame(*request);
      requeue(*request);
      if (frame) return frame;
    }
  }

 private:
  // A libcamera configuration for `config`, adjusting `config` and noting
  // what changed in `v`; nullptr when impossible.
  std::unique_ptr<libcamera::CameraConfiguration> make_configuration(camera::CameraConfig& config,
                                                                     camera::Validation& v) const {
    auto adjust = [&](std::string note) { note_adjusted(v, std::move(note)); };
    auto invalid = [&](std::string note) { note_invalid(v, std::move(note)); };
    std::unique_ptr<libcamera::CameraConfiguration> lc =
        camera_->generateConfiguration({libcamera::StreamRole::Raw});
    if (!lc || lc->empty()) {
      invalid("the camera offers no raw stream");
      return nullptr;
    }
    libcamera::StreamConfiguration& stream = lc->at(0);
    if (config.pixel_format.empty()) config.pixel_format = config_.pixel_format;
    const std::optional<libcamera::PixelFormat> wanted = their_format(config.pixel_format);
    if (!wanted || !our_format(*wanted)) {
      invalid(fmt::format("pixel_format '{}' is not one Lightstage can unpack", config.pixel_format));
      return nullptr;
    }
    stream.pixelFormat = *wanted;
    if (config.size.width > 0 && config.size.height > 0) {
      stream.size = libcamera::Size(static_cast<unsigned>(config.size.width),
                                    static_cast<unsigned>(config.size.height));
    }
    if (config.buffer_count < 1) {
      adjust(fmt::format("buffer_count {} is less than 1; set to 4", config.buffer_count));
      config.buffer_count = 4;
    }
    stream.bufferCount = static_cast<unsigned>(config.buffer_count);
    const libcamera::CameraConfiguration::Status status = lc->validate();
    if (status == libcamera::CameraConfiguration::Invalid) {
      invalid(fmt::format("libcamera rejects {} {}x{}", config.pixel_format, config.size.width,
                          config.size.height));
      return nullptr;
    }
    const PixelFormatDesc* got = our_format(stream.pixelFormat);
    if (!got) {
      invalid(fmt::format("libcamera offers {} instead of {}, which Lightstage cannot unpack",
                          stream.pixelFormat.toString(), config.pixel_format));
      return nullptr;
    }
    if (got->name != config.pixel_format) {
      adjust(
          fmt::format("pixel_format {} is not offered; libcamera chose {}", config.pixel_format, got->name));
      config.pixel_format = std::string(got->name);
    }
    const camera::Size size{static_cast<int>(stream.size.width), static_cast<int>(stream.size.height)};
    if (!(size == config.size)) {
      if (config.size.width > 0 || config.size.height > 0) {
        adjust(fmt::format("size {}x{} is not offered; libcamera chose {}x{}", config.size.width,
                           config.size.height, size.width, size.height));
      }
      config.size = size;
    }
    if (static_cast<int>(stream.bufferCount) != config.buffer_count) {
      adjust(fmt::format("buffer_count {} set to {} by libcamera", config.buffer_count, stream.bufferCount));
      config.buffer_count = static_cast<int>(stream.bufferCount);
    }
    clamp_roi(v, config.roi, size);
    return lc;
  }

  void query_formats() {
    std::unique_ptr<libcamera::CameraConfiguration> lc =
        camera_->generateConfiguration({libcamera::StreamRole::Raw});
    if (!lc || lc->empty()) {
      throw CameraError(Kind::kUnsupported, fmt::format("{}: the camera offers no raw stream", uri()));
    }
    const libcamera::StreamFormats& offered = lc->at(0).formats();
    for (const libcamera::PixelFormat& pf : offered.pixelformats()) {
      const PixelFormatDesc* desc = our_format(pf);
      if (!desc) continue;
      camera::FormatInfo info;
      info.pixel_format = std::string(desc->name);
      info.bit_depth = desc->bit_depth;
      info.cfa = desc->cfa;
      info.description = pf.toString();
      for (const libcamera::Size& s : offered.sizes(pf)) {
        const camera::Size size{static_cast<int>(s.width), static_cast<int>(s.height)};
        info.sizes.push_back({size, size, 1, 1});
      }
      formats_.push_back(std::move(info));
    }
    const libcamera::StreamConfiguration& def = lc->at(0);
    if (const PixelFormatDesc* desc = our_format(def.pixelFormat)) {
      config_.pixel_format = std::string(desc->name);
      config_.size = {static_cast<int>(def.size.width), static_cast<int>(def.size.height)};
    } else if (!formats_.empty() && !formats_.front().sizes.empty()) {
      config_.pixel_format = formats_.front().pixel_format;
      config_.size = formats_.front().sizes.back().max;
    } else {
      throw CameraError(Kind::kUnsupported,
                        fmt::format("{}: the raw stream's formats ({}) are none Lightstage can "
                                    "unpack",
                                    uri(), def.pixelFormat.toString()));
    }
  }

  // Adds the pending manual controls to `list`. Caller holds mutex_.
  void add_controls(libcamera::ControlList& list) {
    if (!pending_exposure_us_ && !pending_gain_) return;
    const libcamera::ControlInfoMap& map = camera_->controls();
    if (map.find(libcamera::controls::AeEnable.id()) != map.end())
      list.set(libcamera::controls::AeEnable, false);
    if (pending_exposure_us_) list.set(libcamera::controls::ExposureTime, *pending_exposure_us_);
    if (pending_gain_) list.set(libcamera::controls::AnalogueGain, *pending_gain_);
  }

  void requeue(libcamera::Request& request) {
    request.reuse(libcamera::Request::ReuseBuffers);
    {
      std::lock_guard lock(mutex_);
      // Every request carries the manual values: a request without them could
      // let a pipeline fall back to its own choice.
      add_controls(request.controls());
    }
    if (const int ret = camera_->queueRequest(&request); ret != 0) fail_ret("queue a request", ret);
  }

  std::optional<camera::Frame> take_frame(libcamera::Request& request) {
    if (request.status() != libcamera::Request::RequestComplete || request.buffers().empty())
      return std::nullopt;
    const libcamera::FrameBuffer* buffer = request.buffers().begin()->second;
    const libcamera::FrameMetadata& meta = buffer->metadata();
    std::uint64_t sequence = (sequence_high_ << 32) | meta.sequence;
    if (have_last_sequence_ && sequence < last_sequence_) sequence = (++sequence_high_ << 32) | meta.sequence;
    last_sequence_ = sequence;
    have_last_sequence_ = true;
    if (meta.status != libcamera::FrameMetadata::FrameSuccess) return std::nullopt;  // the gap shows it

    camera::Frame frame;
    frame.sequence = sequence;
    const libcamera::ControlList& md = request.metadata();
    if (auto ts = md.get(libcamera::controls::SensorTimestamp)) {
      frame.timestamp_ns = *ts;
      frame.clock = camera::ClockDomain::kBoottime;
      frame.timestamp_point = camera::TimestampPoint::kStartOfExposure;
    } else {
      frame.timestamp_ns = static_cast<std::int64_t>(meta.timestamp);
      frame.clock = camera::ClockDomain::kMonotonic;
      frame.timestamp_point = camera::TimestampPoint::kUnknown;
    }
    if (config_.trigger == camera::TriggerMode::kSoftware) {
      if (!trigger_pending_) return std::nullopt;
      const std::int64_t since =
          frame.clock == camera::ClockDomain::kBoottime ? trigger_boottime_ns_ : trigger_monotonic_ns_;
      // A start-of-exposure stamp is exact; a buffer stamp (end of frame) is
      // at most an exposure plus a readout after the exposure began.
      std::int64_t start = frame.timestamp_ns;
      if (frame.timestamp_point != camera::TimestampPoint::kStartOfExposure) {
        start -= static_cast<std::int64_t>(2 * exposure_us_ * 1000.0);
      }
      if (start < since) return std::nullopt;
      trigger_pending_ = false;
    }
    const auto exposure = md.get(libcamera::controls::ExposureTime);
    const auto gain = md.get(libcamera::controls::AnalogueGain);
    frame.controls_reported = exposure.has_value() && gain.has_value();
    frame.exposure_us = exposure ? *exposure : exposure_us_;
    frame.analogue_gain = gain ? *gain : gain_;

    const std::size_t index = static_cast<std::size_t>(request.cookie());
    const Mapping& map = mappings_.at(index);
    const std::size_t used =
        meta.planes().empty() ? map.size : std::min<std::size_t>(meta.planes()[0].bytesused, map.size);
    fill_frame_image(frame, {map.data, used > 0 ? used : map.size}, config_, stride_, *format_, uri(),
                     sequence);
    return frame;
  }

  void release_buffers() {
    requests_.clear();
    for (const auto& m : mappings_) munmap(m.base, m.length);
    mappings_.clear();
    if (allocator_ && stream_) allocator_->free(stream_);
    allocator_.reset();
  }

  // Runs on libcamera's thread.
  void request_completed(libcamera::Request* request) {
    if (request->status() == libcamera::Request::RequestCancelled) return;  // stop(): reused in stop()
    {
      std::lock_guard lock(mutex_);
      completed_.push_back(request);
    }
    ready_.notify_one();
  }

  void camera_disconnected() {
    {
      std::lock_guard lock(mutex_);
      disconnected_ = true;
    }
    ready_.notify_all();
  }

  [[noreturn]] void fail_ret(const char* what, int ret) {
    if (ret == -ENODEV)
      throw CameraError(Kind::kDisconnected, fmt::format("{}: {}: camera disconnected", uri(), what));
    if (ret == -EBUSY) throw CameraError(Kind::kBusy, fmt::format("{}: {}: camera busy", uri(), what));
    if (ret == -EACCES) {
      throw CameraError(fmt::format("{}: {}: not allowed in the camera's current state", uri(), what));
    }
    throw CameraError(fmt::format("{}: {} failed: {}", uri(), what, std::strerror(-ret)));
  }

  std::shared_ptr<libcamera::CameraManager> manager_;  // outlives camera_ (declared first, destroyed last)
  std::shared_ptr<libcamera::Camera> camera_;
  std::string id_;
  std::string model_;
  std::vector<camera::FormatInfo> formats_;
  camera::CameraConfig config_;
  camera::CameraConfig initial_config_;

  std::unique_ptr<libcamera::CameraConfiguration> configuration_;
  libcamera::Stream* stream_ = nullptr;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator_;
  std::vector<std::unique_ptr<libcamera::Request>> requests_;
  std::vector<Mapping> mappings_;
  const PixelFormatDesc* format_ = nullptr;
  std::size_t stride_ = 0;
  bool streaming_ = false;

  std::mutex mutex_;  // guards what libcamera's thread touches, and the pending controls
  std::condition_variable ready_;
  std::deque<libcamera::Request*> completed_;
  bool disconnected_ = false;
  std::optional<std::int32_t> pending_exposure_us_;
  std::optional<float> pending_gain_;

  double exposure_us_ = 0;
  double gain_ = 1;
  std::uint64_t sequence_high_ = 0;
  std::uint64_t last_sequence_ = 0;
  bool have_last_sequence_ = false;
  bool trigger_pending_ = false;
  std::int64_t trigger_boottime_ns_ = 0;
  std::int64_t trigger_monotonic_ns_ = 0;
};

}  // namespace

std::shared_ptr<libcamera::CameraManager> shared_camera_manager() {
  static std::mutex mutex;
  static std::weak_ptr<libcamera::CameraManager> current;
  std::lock_guard lock(mutex);
  if (auto manager = current.lock()) return manager;
  auto fresh = std::make_unique<libcamera::CameraManager>();
  if (const int ret = fresh->start(); ret != 0) {
    throw CameraError(fmt::format("libcamera: the camera manager failed to start: {}", std::strerror(-ret)));
  }
  std::shared_ptr<libcamera::CameraManager> manager(fresh.release(), [](libcamera::CameraManager* m) {
    m->stop();
    delete m;
  });
  current = manager;
  return manager;
}

std::vector<std::string> libcamera_camera_ids(const libcamera::CameraManager& manager) {
  std::vector<std::string> ids;
  for (const auto& cam : manager.cameras()) ids.push_back(cam->id());
  return ids;
}

camera::CameraScheme libcamera_camera_scheme() {
  camera::CameraScheme scheme;
  scheme.scheme = "libcamera";
  scheme.form = "libcamera:ID";
  scheme.open = [](const camera::CameraUri& uri) -> std::unique_ptr<camera::Camera> {
    return std::make_unique<LibcameraCamera>(uri, shared_camera_manager());
  };
  scheme.list = [] {
    std::vector<camera::CameraInfo> found;
    const auto manager = shared_camera_manager();
    for (const auto& cam : manager->cameras()) {
      const std::string model = cam->properties().get(libcamera::properties::Model).value_or(cam->id());
      found.push_back({"libcamera:" + cam->id(), model, "libcamera"});
    }
    return found;
  };
  return scheme;
}

}  // namespace lightstage::hw
