// The v4l2: camera: a single-planar Video4Linux2 capture node with mmap
// streaming. Every system call goes through V4l2Syscalls (v4l2_camera.hpp).
#include "lightstage/hw/v4l2_camera.hpp"

#include "backend_common.hpp"
#include "lightstage/hw/cameras.hpp"
#include "lightstage/hw/pixel_formats.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <span>
#include <stdexcept>

namespace lightstage::hw {

// Our format table spells the kernel's fourccs itself; check it against the header.
static_assert(fourcc('G', 'R', 'E', 'Y') == V4L2_PIX_FMT_GREY);
static_assert(fourcc('Y', '1', '6', ' ') == V4L2_PIX_FMT_Y16);
static_assert(fourcc('B', 'Y', 'R', '2') == V4L2_PIX_FMT_SBGGR16);
static_assert(fourcc('p', 'R', 'C', 'C') == V4L2_PIX_FMT_SRGGB12P);
static_assert(fourcc('B', 'A', '1', '0') == V4L2_PIX_FMT_SGRBG10);

namespace {

using camera::CameraError;
using Kind = camera::CameraError::Kind;

class SystemSyscalls final : public V4l2Syscalls {
 public:
  int open(const char* path, int flags) override { return ::open(path, flags); }
  int close(int fd) override { return ::close(fd); }
  int ioctl(int fd, unsigned long request, void* arg) override { return ::ioctl(fd, request, arg); }
  void* mmap(std::size_t length, int prot, int flags, int fd, off_t offset) override {
    return ::mmap(nullptr, length, prot, flags, fd, offset);
  }
  int munmap(void* addr, std::size_t length) override { return ::munmap(addr, length); }
  int poll(pollfd* fds, nfds_t count, int timeout_ms) override { return ::poll(fds, count, timeout_ms); }
};

std::string fourcc_text(std::uint32_t code) {
  std::string text;
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((code >> (8 * i)) & 0xff);
    text += (c >= 32 && c < 127) ? c : '?';
  }
  return text;
}

// One V4L2 control as found by VIDIOC_QUERYCTRL.
struct Ctrl {
  std::uint32_t id = 0;
  bool present = false;
  std::int32_t min = 0, max = 0, step = 1, def = 0;
};

struct Buffer {
  void* data = nullptr;
  std::size_t length = 0;
};

class V4l2Camera final : public camera::Camera {
 public:
  V4l2Camera(const camera::CameraUri& uri, std::string path, std::shared_ptr<V4l2Syscalls> sys)
      : Camera(uri.uri), path_(std::move(path)), sys_(std::move(sys)) {
    if (auto unit = uri.option("exposure_unit_us"))
      exposure_unit_option_ = parse_positive(uri, "exposure_unit_us", *unit);
    if (auto unity = uri.option("gain_unity")) gain_unity_option_ = parse_positive(uri, "gain_unity", *unity);
    for (const auto& [key, value] : uri.options) {
      if (key != "exposure_unit_us" && key != "gain_unity") {
        fail("camera URI '{}': unknown option '{}' (v4l2: takes exposure_unit_us, gain_unity)", uri.uri, key);
      }
    }
    open_device();
    try {
      query_formats();
      query_controls();
      if (!formats_.empty()) {
        config_.pixel_format = formats_.front().pixel_format;
        config_.size = largest_size(formats_.front());
      }
      // The format in force when we opened: configure() is required only to change it.
      v4l2_format fmt{};
      fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      if (xioctl(VIDIOC_G_FMT, &fmt) == 0) adopt_format(fmt.fmt.pix);
      initial_config_ = config_;
    } catch (...) {
      sys_->close(fd_);
      throw;
    }
  }

  ~V4l2Camera() override {
    try {
      stop();
    } catch (const std::exception&) {
      // The device is going away with us; nothing left to report to.
    }
    sys_->close(fd_);
  }

  camera::CameraInfo info() const override { return {uri(), card_, driver_}; }

  std::vector<camera::FormatInfo> formats() const override { return formats_; }

  std::vector<camera::TriggerMode> trigger_modes() const override {
    return {camera::TriggerMode::kFreeRun, camera::TriggerMode::kSoftware, camera::TriggerMode::kHardware};
  }

  camera::CameraConfig default_config() const override { return initial_config_; }

  camera::Validation validate(camera::CameraConfig& config) const override {
    camera::Validation v;
    // VIDIOC_ENUM_FRAMESIZES is per format: a size note names it.
    validate_offered(v, config, formats_, config_.pixel_format, /*name_format=*/true, 32);
    return v;
  }

  void configure(const camera::CameraConfig& requested) override {
    const camera::CameraConfig config = require_configurable(*this, requested, streaming_, uri());
    const PixelFormatDesc* desc = find_pixel_format(config.pixel_format);
    v4l2_format fmt{};
    fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    fmt.fmt.pix.width = static_cast<std::uint32_t>(config.size.width);
    fmt.fmt.pix.height = static_cast<std::uint32_t>(config.size.height);
    fmt.fmt.pix.pixelformat = desc->v4l2_fourcc;
    fmt.fmt.pix.field = V4L2_FIELD_NONE;
    if (const int err = xioctl(VIDIOC_S_FMT, &fmt)) fail_errno("VIDIOC_S_FMT", err);
    if (fmt.fmt.pix.pixelformat != desc->v4l2_fourcc ||
        fmt.fmt.pix.width != static_cast<std::uint32_t>(config.size.width) ||
        fmt.fmt.pix.height != static_cast<std::uint32_t>(config.size.height)) {
      throw CameraError(fmt::format(
          "{}: asked for {} {}x{}, the driver set {} {}x{}", uri(), config.pixel_format, config.size.width,
          config.size.height, fourcc_text(fmt.fmt.pix.pixelformat), fmt.fmt.pix.width, fmt.fmt.pix.height));
    }
    adopt_format(fmt.fmt.pix);
    config_ = config;
  }

  camera::CameraConfig configuration() const override { return config_; }

  camera::ControlInfo control_info() const override {
    camera::ControlInfo info;
    info.latency_frames = 2;
    if (const Ctrl* e = exposure_ctrl(); e && exposure_unit_us() > 0) {
      info.exposure_min_us = e->min * exposure_unit_us();
      info.exposure_max_us = e->max * exposure_unit_us();
      info.exposure_step_us = e->step * exposure_unit_us();
    }
    if (const Ctrl* g = gain_ctrl()) {
      info.gain_min = g->min / gain_unity();
      info.gain_max = g->max / gain_unity();
    }
    return info;
  }

  camera::Controls set_controls(const camera::Controls& controls) override {
    if (controls.exposure_us) {
      const Ctrl* e = exposure_ctrl();
      if (!e) throw CameraError(Kind::kUnsupported, fmt::format("{}: has no exposure control", uri()));
      const double unit = exposure_unit_us();
      if (unit <= 0) {
        throw CameraError(Kind::kUnsupported,
                          fmt::format("{}: V4L2_CID_EXPOSURE counts device units (lines) and the node has no "
                                      "V4L2_CID_PIXEL_RATE/V4L2_CID_HBLANK to convert microseconds; give the "
                                      "line time in the URI, e.g. {}?exposure_unit_us=14.7",
                                      uri(), uri()));
      }
      if (auto_exposure_.present) set_ctrl(auto_exposure_, V4L2_EXPOSURE_MANUAL, "V4L2_CID_EXPOSURE_AUTO");
      const std::int32_t code =
          to_code(*e, *controls.exposure_us / unit, "exposure_us", *controls.exposure_us, unit);
      exposure_us_ =
          set_ctrl(*e, code,
                   e->id == V4L2_CID_EXPOSURE_ABSOLUTE ? "V4L2_CID_EXPOSURE_ABSOLUTE" : "V4L2_CID_EXPOSURE") *
          unit;
    }
    if (controls.analogue_gain) {
      const Ctrl* g = gain_ctrl();
      if (!g) throw CameraError(Kind::kUnsupported, fmt::format("{}: has no gain control", uri()));
      if (auto_gain_.present) set_ctrl(auto_gain_, 0, "V4L2_CID_AUTOGAIN");
      const double unity = gain_unity();
      const std::int32_t code =
          to_code(*g, *controls.analogue_gain * unity, "analogue_gain", *controls.analogue_gain, 1.0 / unity);
      gain_ =
          set_ctrl(*g, code, g->id == V4L2_CID_ANALOGUE_GAIN ? "V4L2_CID_ANALOGUE_GAIN" : "V4L2_CID_GAIN") /
          unity;
    }
    return {exposure_us_, gain_};
  }

  void start() override {
    if (streaming_) return;
    if (!format_) configure(config_);  // the driver's format at open is not one we unpack: use ours
    v4l2_requestbuffers req{};
    req.count = static_cast<std::uint32_t>(config_.buffer_count);
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    if (const int err = xioctl(VIDIOC_REQBUFS, &req)) fail_errno("VIDIOC_REQBUFS", err);
    if (req.count < 2) {
      release_buffers();
      throw CameraError(
          fmt::format("{}: the driver granted {} buffer(s); streaming needs at least 2", uri(), req.count));
    }
    try {
      for (std::uint32_t i = 0; i < req.count; ++i) {
        v4l2_buffer buf{};
        buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        buf.memory = V4L2_MEMORY_MMAP;
        buf.index = i;
        if (const int err = xioctl(VIDIOC_QUERYBUF, &buf)) fail_errno("VIDIOC_QUERYBUF", err);
        void* data = sys_->mmap(buf.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, buf.m.offset);
        if (data == MAP_FAILED) fail_errno("mmap", errno);
        buffers_.push_back({data, buf.length});
      }
      for (std::uint32_t i = 0; i < req.count; ++i) queue_buffer(i);
      int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      if (const int err = xioctl(VIDIOC_STREAMON, &type)) fail_errno("VIDIOC_STREAMON", err);
    } catch (...) {
      release_buffers();
      throw;
    }
    streaming_ = true;
    have_last_sequence_ = false;
    last_timestamp_ns_ = 0;
    trigger_pending_ = false;
  }

  void stop() override {
    if (!streaming_ && buffers_.empty()) return;
    streaming_ = false;
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    const int err = xioctl(VIDIOC_STREAMOFF, &type);
    release_buffers();
    if (err != 0 && err != ENODEV) fail_errno("VIDIOC_STREAMOFF", err);
  }

  bool streaming() const override { return streaming_; }

  void trigger() override {
    check_software_trigger(config_, streaming_, uri());
    trigger_pending_ = true;
    trigger_time_ns_ = camera::clock_now_ns(camera::ClockDomain::kMonotonic);
    frames_since_trigger_ = 0;
  }

  std::optional<camera::Frame> wait_frame(std::chrono::milliseconds timeout) override {
    if (!streaming_)
      throw CameraError(fmt::format("{}: wait_frame() while not streaming; start() first", uri()));
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      pollfd p{fd_, POLLIN, 0};
      const int ready = sys_->poll(&p, 1, static_cast<int>(std::max<std::int64_t>(0, left.count())));
      if (ready < 0) {
        if (errno == EINTR) continue;
        fail_errno("poll", errno);
      }
      if (ready == 0) return std::nullopt;
      // POLLERR / POLLHUP too: DQBUF then says what happened (ENODEV when unplugged).
      v4l2_buffer buf{};
      buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      buf.memory = V4L2_MEMORY_MMAP;
      if (const int err = xioctl(VIDIOC_DQBUF, &buf)) {
        if (err == EAGAIN) {
          if (p.revents & (POLLERR | POLLHUP)) {
            throw CameraError(Kind::kDisconnected,
                              fmt::format("{}: the device reports an error (poll)", uri()));
          }
          continue;
        }
        fail_errno("VIDIOC_DQBUF", err);
      }
      std::optional<camera::Frame> frame = take_frame(buf);
      queue_buffer(buf.index);
      if (frame) return frame;
      // Skipped: look again (a poll with no time left still finds frames already waiting).
    }
  }

 private:
  void open_device() {
    fd_ = sys_->open(path_.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0) {
      const int err = errno;
      if (err == ENOENT || err == ENXIO || err == ENODEV) {
        throw CameraError(Kind::kNotFound,
                          fmt::format("{}: no such device ({}); `lightstage devices` lists the "
                                      "cameras this machine sees",
                                      uri(), std::strerror(err)));
      }
      if (err == EACCES || err == EPERM) {
        throw CameraError(
            fmt::format("{}: permission denied opening {}; add the user to group 'video' "
                        "(see hw/docs/cameras.md)",
                        uri(), path_));
      }
      if (err == EBUSY) throw CameraError(Kind::kBusy, fmt::format("{}: device busy", uri()));
      throw CameraError(fmt::format("{}: cannot open {}: {}", uri(), path_, std::strerror(err)));
    }
    v4l2_capability cap{};
    if (const int err = xioctl(VIDIOC_QUERYCAP, &cap)) {
      sys_->close(fd_);
      if (err == ENOTTY || err == EINVAL) {
        throw CameraError(Kind::kUnsupported, fmt::format("{}: {} is not a V4L2 device", uri(), path_));
      }
      throw CameraError(fmt::format("{}: VIDIOC_QUERYCAP failed: {}", uri(), std::strerror(err)));
    }
    const std::uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
    driver_ = reinterpret_cast<const char*>(cap.driver);
    card_ = reinterpret_cast<const char*>(cap.card);
    std::string missing;
    if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) {
      missing =
          (caps & V4L2_CAP_VIDEO_CAPTURE_MPLANE)
              ? "single-planar video capture (this is a multi-planar node, not supported yet)"
              : "video capture (is it a metadata or output node? try the other /dev/video* of this card)";
    } else if (!(caps & V4L2_CAP_STREAMING)) {
      missing = "streaming I/O";
    }
    if (!missing.empty()) {
      sys_->close(fd_);
      throw CameraError(Kind::kUnsupported, fmt::format("{}: {} ({}, driver {}) lacks {}", uri(), path_,
                                                        card_, driver_, missing));
    }
  }

  void query_formats() {
    for (std::uint32_t index = 0;; ++index) {
      v4l2_fmtdesc desc{};
      desc.index = index;
      desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      if (const int err = xioctl(VIDIOC_ENUM_FMT, &desc)) {
        if (err == EINVAL) break;
        fail_errno("VIDIOC_ENUM_FMT", err);
      }
      const PixelFormatDesc* known = find_v4l2_pixel_format(desc.pixelformat);
      if (!known) {
        unknown_formats_.push_back(fourcc_text(desc.pixelformat));
        continue;
      }
      camera::FormatInfo info;
      info.pixel_format = std::string(known->name);
      info.bit_depth = known->bit_depth;
      info.cfa = known->cfa;
      info.description = reinterpret_cast<const char*>(desc.description);
      for (std::uint32_t size_index = 0;; ++size_index) {
        v4l2_frmsizeenum size{};
        size.index = size_index;
        size.pixel_format = desc.pixelformat;
        if (xioctl(VIDIOC_ENUM_FRAMESIZES, &size) != 0) break;
        if (size.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
          const camera::Size s{static_cast<int>(size.discrete.width), static_cast<int>(size.discrete.height)};
          info.sizes.push_back({s, s, 1, 1});
        } else {
          const auto& sw = size.stepwise;
          info.sizes.push_back({{static_cast<int>(sw.min_width), static_cast<int>(sw.min_height)},
                                {static_cast<int>(sw.max_width), static_cast<int>(sw.max_height)},
                                static_cast<int>(std::max(1u, sw.step_width)),
                                static_cast<int>(std::max(1u, sw.step_height))});
          break;  // stepwise and continuous come as one entry
        }
      }
      if (info.sizes.empty()) {
        // No ENUM_FRAMESIZES: the current size is the one we know.
        v4l2_format fmt{};
        fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        if (xioctl(VIDIOC_G_FMT, &fmt) == 0) {
          const camera::Size s{static_cast<int>(fmt.fmt.pix.width), static_cast<int>(fmt.fmt.pix.height)};
          info.sizes.push_back({s, s, 1, 1});
        }
      }
      formats_.push_back(std::move(info));
    }
    if (formats_.empty()) {
      std::string offered;
      for (const auto& f : unknown_formats_) offered += (offered.empty() ? "" : ", ") + f;
      throw CameraError(
          Kind::kUnsupported,
          fmt::format("{}: offers no pixel format Lightstage can unpack (offers: {}; wanted GREY, "
                      "Y10, Y12, Y16, YUYV or Bayer 8/10/12/16)",
                      uri(), offered.empty() ? "none" : offered));
    }
  }

  Ctrl query_ctrl(std::uint32_t id) {
    Ctrl ctrl;
    ctrl.id = id;
    v4l2_queryctrl q{};
    q.id = id;
    if (xioctl(VIDIOC_QUERYCTRL, &q) == 0 && !(q.flags & V4L2_CTRL_FLAG_DISABLED)) {
      ctrl.present = true;
      ctrl.min = q.minimum;
      ctrl.max = q.maximum;
      ctrl.step = std::max(1, q.step);
      ctrl.def = q.default_value;
    }
    return ctrl;
  }

  void query_controls() {
    auto_exposure_ = query_ctrl(V4L2_CID_EXPOSURE_AUTO);
    exposure_absolute_ = query_ctrl(V4L2_CID_EXPOSURE_ABSOLUTE);
    exposure_lines_ = query_ctrl(V4L2_CID_EXPOSURE);
    auto_gain_ = query_ctrl(V4L2_CID_AUTOGAIN);
    analogue_gain_ = query_ctrl(V4L2_CID_ANALOGUE_GAIN);
    gain_plain_ = query_ctrl(V4L2_CID_GAIN);
    hblank_ = query_ctrl(V4L2_CID_HBLANK);
    v4l2_ext_control rate{};
    rate.id = V4L2_CID_PIXEL_RATE;
    v4l2_ext_controls list{};
    list.which = V4L2_CTRL_WHICH_CUR_VAL;
    list.count = 1;
    list.controls = &rate;
    if (xioctl(VIDIOC_G_EXT_CTRLS, &list) == 0 && rate.value64 > 0) pixel_rate_ = rate.value64;
    if (const Ctrl* e = exposure_ctrl()) {
      v4l2_control c{e->id, 0};
      if (xioctl(VIDIOC_G_CTRL, &c) == 0 && exposure_unit_us() > 0)
        exposure_us_ = c.value * exposure_unit_us();
    }
    if (const Ctrl* g = gain_ctrl()) {
      v4l2_control c{g->id, 0};
      if (xioctl(VIDIOC_G_CTRL, &c) == 0) gain_ = c.value / gain_unity();
    }
  }

  const Ctrl* exposure_ctrl() const {
    if (exposure_absolute_.present) return &exposure_absolute_;
    if (exposure_lines_.present) return &exposure_lines_;
    return nullptr;
  }
  const Ctrl* gain_ctrl() const {
    if (analogue_gain_.present) return &analogue_gain_;
    if (gain_plain_.present) return &gain_plain_;
    return nullptr;
  }

  // µs per exposure-control step, 0 when unknown.
  double exposure_unit_us() const {
    if (exposure_absolute_.present) return 100.0;  // V4L2_CID_EXPOSURE_ABSOLUTE counts 100 µs
    if (exposure_unit_option_ > 0) return exposure_unit_option_;
    if (pixel_rate_ > 0 && hblank_.present && width_px_ > 0) {
      // One line: (active width + horizontal blanking) pixels at the pixel rate.
      v4l2_control c{V4L2_CID_HBLANK, 0};
      std::int32_t hblank = hblank_.def;
      if (xioctl(VIDIOC_G_CTRL, &c) == 0) hblank = c.value;
      return (width_px_ + hblank) * 1e6 / static_cast<double>(pixel_rate_);
    }
    return 0;
  }

  double gain_unity() const {
    if (gain_unity_option_ > 0) return gain_unity_option_;
    const Ctrl* g = gain_ctrl();
    return (g && g->def > 0) ? g->def : 1.0;
  }

  // The control value for `value` (already in control units), rounded to its
  // step; out of range throws naming the field, value and range (in user units).
  std::int32_t to_code(const Ctrl& ctrl, double value, const char* field, double user_value,
                       double unit) const {
    const double half_step = ctrl.step / 2.0;
    if (!std::isfinite(value) || value < ctrl.min - half_step || value > ctrl.max + half_step) {
      throw CameraError(fmt::format("{}: {} {} is outside the camera's range [{}, {}]", uri(), field,
                                    user_value, ctrl.min * unit, ctrl.max * unit));
    }
    const double steps = std::round((value - ctrl.min) / ctrl.step);
    return std::clamp(static_cast<std::int32_t>(ctrl.min + steps * ctrl.step), ctrl.min, ctrl.max);
  }

  // Sets a control and returns the value the driver now holds.
  std::int32_t set_ctrl(const Ctrl& ctrl, std::int32_t value, const char* name) {
    v4l2_control c{ctrl.id, value};
    if (const int err = xioctl(VIDIOC_S_CTRL, &c))
      fail_errno(fmt::format("VIDIOC_S_CTRL {}={}", name, value), err);
    v4l2_control read{ctrl.id, 0};
    if (xioctl(VIDIOC_G_CTRL, &read) == 0) return read.value;
    return value;
  }

  void adopt_format(const v4l2_pix_format& pix) {
    const PixelFormatDesc* desc = find_v4l2_pixel_format(pix.pixelformat);
    if (!desc) return;  // a format we cannot unpack: configure() must pick another before start()
    config_.pixel_format = std::string(desc->name);
    config_.size = {static_cast<int>(pix.width), static_cast<int>(pix.height)};
    format_ = desc;
    width_px_ = static_cast<int>(pix.width);
    stride_ =
        std::max<std::size_t>(pix.bytesperline, min_row_bytes(desc->packing, static_cast<int>(pix.width)));
  }

  void queue_buffer(std::uint32_t index) {
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = index;
    if (const int err = xioctl(VIDIOC_QBUF, &buf)) fail_errno("VIDIOC_QBUF", err);
  }

  void release_buffers() {
    for (const auto& b : buffers_) sys_->munmap(b.data, b.length);
    buffers_.clear();
    v4l2_requestbuffers req{};
    req.count = 0;
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    xioctl(VIDIOC_REQBUFS, &req);  // best effort: fails harmlessly once the device is gone
  }

  // The frame in buffer `buf`, or nullopt when it is to be skipped (a driver
  // error flag, or a frame exposed before the software trigger).
  std::optional<camera::Frame> take_frame(const v4l2_buffer& buf) {
    if (buf.index >= buffers_.size()) {
      throw CameraError(
          fmt::format("{}: driver returned buffer index {} of {}", uri(), buf.index, buffers_.size()));
    }
    // Sequence numbers are 32-bit in V4L2; extend across wrap-around.
    std::uint64_t sequence = (sequence_high_ << 32) | buf.sequence;
    if (have_last_sequence_ && sequence < last_sequence_) {
      ++sequence_high_;
      sequence = (sequence_high_ << 32) | buf.sequence;
    }
    last_sequence_ = sequence;
    have_last_sequence_ = true;
    const std::int64_t ts = static_cast<std::int64_t>(buf.timestamp.tv_sec) * 1'000'000'000 +
                            static_cast<std::int64_t>(buf.timestamp.tv_usec) * 1000;
    const std::int64_t previous_ts = last_timestamp_ns_;
    last_timestamp_ns_ = ts;
    if (buf.flags & V4L2_BUF_FLAG_ERROR) return std::nullopt;  // corrupt: the gap in sequence shows it

    const auto clock = (buf.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC
                           ? camera::ClockDomain::kMonotonic
                           : camera::ClockDomain::kUnknown;
    const auto point = (buf.flags & V4L2_BUF_FLAG_TSTAMP_SRC_MASK) == V4L2_BUF_FLAG_TSTAMP_SRC_SOE
                           ? camera::TimestampPoint::kStartOfExposure
                           : camera::TimestampPoint::kEndOfFrame;
    if (config_.trigger == camera::TriggerMode::kSoftware) {
      if (!trigger_pending_) return std::nullopt;
      ++frames_since_trigger_;
      if (clock == camera::ClockDomain::kMonotonic) {
        // The earliest the exposure can have begun: a start-of-exposure stamp
        // is exact; an end-of-frame stamp is at most exposure + one frame
        // interval (readout) after it.
        std::int64_t start = ts;
        if (point == camera::TimestampPoint::kEndOfFrame) {
          start -= static_cast<std::int64_t>(exposure_us_ * 1000.0);
          start -= previous_ts > 0 && ts > previous_ts ? ts - previous_ts : 0;
        }
        if (start < trigger_time_ns_) return std::nullopt;
      } else if (frames_since_trigger_ < 2) {
        return std::nullopt;  // unknown clock: the second frame after the trigger is surely exposed after it
      }
      trigger_pending_ = false;
    }

    const Buffer& mem = buffers_[buf.index];
    const std::size_t used =
        buf.bytesused > 0 ? std::min<std::size_t>(buf.bytesused, mem.length) : mem.length;
    camera::Frame frame;
    fill_frame_image(frame, {static_cast<const std::uint8_t*>(mem.data), used}, config_, stride_, *format_,
                     uri(), sequence);
    frame.sequence = sequence;
    frame.timestamp_ns = ts;
    frame.clock = clock;
    frame.timestamp_point = point;
    frame.exposure_us = exposure_us_;
    frame.analogue_gain = gain_;
    frame.controls_reported = false;
    return frame;
  }

  // ioctl, retried on EINTR; 0 or the errno.
  int xioctl(unsigned long request, void* arg) const {
    for (;;) {
      if (sys_->ioctl(fd_, request, arg) == 0) return 0;
      if (errno != EINTR) return errno;
    }
  }

  [[noreturn]] void fail_errno(const std::string& what, int err) {
    if (err == ENODEV) {
      streaming_ = false;
      throw CameraError(Kind::kDisconnected,
                        fmt::format("{}: device disconnected ({}: {})", uri(), what, std::strerror(err)));
    }
    if (err == EBUSY)
      throw CameraError(Kind::kBusy,
                        fmt::format("{}: {}: device busy (another process streaming?)", uri(), what));
    throw CameraError(fmt::format("{}: {} failed: {}", uri(), what, std::strerror(err)));
  }

  std::string path_;
  std::shared_ptr<V4l2Syscalls> sys_;
  int fd_ = -1;
  std::string driver_, card_;
  std::vector<camera::FormatInfo> formats_;
  std::vector<std::string> unknown_formats_;
  camera::CameraConfig config_;
  camera::CameraConfig initial_config_;
  const PixelFormatDesc* format_ = nullptr;
  int width_px_ = 0;
  std::size_t stride_ = 0;

  Ctrl auto_exposure_, exposure_absolute_, exposure_lines_, auto_gain_, analogue_gain_, gain_plain_, hblank_;
  std::int64_t pixel_rate_ = 0;
  double exposure_unit_option_ = 0;
  double gain_unity_option_ = 0;
  double exposure_us_ = 0;
  double gain_ = 1;

  std::vector<Buffer> buffers_;
  bool streaming_ = false;
  std::uint64_t sequence_high_ = 0;
  std::uint64_t last_sequence_ = 0;
  bool have_last_sequence_ = false;
  std::int64_t last_timestamp_ns_ = 0;
  bool trigger_pending_ = false;
  std::int64_t trigger_time_ns_ = 0;
  int frames_since_trigger_ = 0;
};

std::string device_path(const camera::CameraUri& uri) {
  const std::string& t = uri.target;
  if (t.empty()) fail("camera URI '{}': give the device, e.g. v4l2:/dev/video0", uri.uri);
  if (std::all_of(t.begin(), t.end(), [](char c) { return c >= '0' && c <= '9'; })) return "/dev/video" + t;
  if (t.front() != '/')
    fail("camera URI '{}': '{}' is not a device path (v4l2:/dev/videoN or v4l2:N)", uri.uri, t);
  return t;
}

}  // namespace

std::shared_ptr<V4l2Syscalls> system_v4l2_syscalls() { return std::make_shared<SystemSyscalls>(); }

std::unique_ptr<camera::Camera> open_v4l2_camera(const camera::CameraUri& uri,
                                                 std::shared_ptr<V4l2Syscalls> sys) {
  if (uri.scheme != "v4l2") fail("camera URI '{}': not a v4l2: URI", uri.uri);
  return std::make_unique<V4l2Camera>(uri, device_path(uri), std::move(sys));
}

camera::CameraScheme v4l2_camera_scheme() {
  camera::CameraScheme scheme;
  scheme.scheme = "v4l2";
  scheme.form = "v4l2:/dev/videoN";
  scheme.open = [](const camera::CameraUri& uri) { return open_v4l2_camera(uri); };
  scheme.list = [] {
    std::vector<camera::CameraInfo> found;
    std::error_code ec;
    std::vector<std::string> paths;
    for (const auto& entry : std::filesystem::directory_iterator("/dev", ec)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("video", 0) == 0) paths.push_back(entry.path().string());
    }
    std::sort(paths.begin(), paths.end());
    for (const auto& path : paths) {
      try {
        auto cam = open_v4l2_camera(camera::parse_camera_uri("v4l2:" + path));
        found.push_back(cam->info());
      } catch (const std::exception&) {
        // Not a capture node we can use (metadata nodes, codecs, busy devices).
      }
    }
    return found;
  };
  return scheme;
}

}  // namespace lightstage::hw
