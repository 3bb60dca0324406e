// The aravis:ID camera: a GenICam camera (GigE Vision or USB3 Vision)
// through aravis 0.8 (0.8.26 in Debian 12), driven by its standard features:
// PixelFormat, Width/Height/OffsetX/OffsetY, ExposureAuto/ExposureTime,
// GainAuto/Gain, TriggerSelector/TriggerMode/TriggerSource/TriggerActivation.
//
// Frames: aravis's stream thread fills the buffers; wait_frame() pops one,
// copies the image out and pushes the buffer back. Each frame carries the
// camera's frame id as its sequence and arv_buffer_get_system_timestamp() as
// its time: aravis 0.8 stamps a buffer with g_get_real_time() (CLOCK_REALTIME)
// when the frame's first packet (the leader) arrives, which is after the
// exposure ended -- hence ClockDomain::kRealtime and TimestampPoint::kEndOfFrame.
// (The camera's own clock, arv_buffer_get_timestamp(), is on no host clock.)
#include "backend_common.hpp"
#include "lightstage/hw/cameras.hpp"
#include "lightstage/hw/pixel_formats.hpp"

#include <arv.h>

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <string_view>

namespace lightstage::hw {

namespace {

using camera::CameraError;
using Kind = camera::CameraError::Kind;

// GenICam (PFNC) names of the unpacked formats we deliver, under our names.
// PFNC's packed formats (Mono12p, BayerRG12Packed, ...) pack differently from
// the CSI-2 layouts pixel_formats.hpp unpacks, so they are not offered.
struct FormatName {
  std::string_view genicam;
  std::string_view ours;
};
constexpr FormatName kFormats[] = {
    {"Mono8", "GREY"},        {"Mono10", "Y10"},        {"Mono12", "Y12"},        {"Mono16", "Y16"},
    {"BayerRG8", "SRGGB8"},   {"BayerBG8", "SBGGR8"},   {"BayerGR8", "SGRBG8"},   {"BayerGB8", "SGBRG8"},
    {"BayerRG10", "SRGGB10"}, {"BayerBG10", "SBGGR10"}, {"BayerGR10", "SGRBG10"}, {"BayerGB10", "SGBRG10"},
    {"BayerRG12", "SRGGB12"}, {"BayerBG12", "SBGGR12"}, {"BayerGR12", "SGRBG12"}, {"BayerGB12", "SGBRG12"},
    {"BayerRG16", "SRGGB16"}, {"BayerBG16", "SBGGR16"}, {"BayerGR16", "SGRBG16"}, {"BayerGB16", "SGBRG16"},
};

std::string_view genicam_name(std::string_view ours) {
  for (const auto& f : kFormats) {
    if (f.ours == ours) return f.genicam;
  }
  return {};
}

std::string_view our_name(std::string_view genicam) {
  for (const auto& f : kFormats) {
    if (f.genicam == genicam) return f.ours;
  }
  return {};
}

template <typename T>
struct Unref {
  void operator()(T* p) const { g_object_unref(p); }
};
using ArvCameraPtr = std::unique_ptr<ArvCamera, Unref<ArvCamera>>;
using StreamPtr = std::unique_ptr<ArvStream, Unref<ArvStream>>;

// A GError the called function may set; freed on scope exit.
class GErrorHolder {
 public:
  GErrorHolder() = default;
  GErrorHolder(const GErrorHolder&) = delete;
  GErrorHolder& operator=(const GErrorHolder&) = delete;
  ~GErrorHolder() { clear(); }
  GError** out() {
    clear();
    return &error_;
  }
  const GError* get() const { return error_; }
  explicit operator bool() const { return error_ != nullptr; }
  void clear() {
    if (error_) g_error_free(error_);
    error_ = nullptr;
  }

 private:
  GError* error_ = nullptr;
};

// An aravis failure as a CameraError: the URI, what was being done, aravis's message.
[[noreturn]] void throw_arv(const std::string& uri, std::string_view operation, const GError* error) {
  Kind kind = Kind::kFailed;
  std::string advice;
  if (error->domain == ARV_DEVICE_ERROR) {
    switch (error->code) {
      case ARV_DEVICE_ERROR_NOT_FOUND:
        kind = Kind::kNotFound;
        break;
      case ARV_DEVICE_ERROR_NOT_CONTROLLER:
      case ARV_DEVICE_ERROR_PROTOCOL_ERROR_ACCESS_DENIED:
      case ARV_DEVICE_ERROR_PROTOCOL_ERROR_BUSY:
        kind = Kind::kBusy;
        advice = "another program or host controls the camera (arv-viewer, a vendor tool); close it";
        break;
      case ARV_DEVICE_ERROR_NOT_CONNECTED:
      case ARV_DEVICE_ERROR_TIMEOUT:
      case ARV_DEVICE_ERROR_TRANSFER_ERROR:
        kind = Kind::kDisconnected;
        advice = "the camera does not answer (unplugged, powered off, or its network is down)";
        break;
      case ARV_DEVICE_ERROR_FEATURE_NOT_FOUND:
        kind = Kind::kUnsupported;
        break;
      default:
        break;
    }
  } else if (error->domain == ARV_GC_ERROR && (error->code == ARV_GC_ERROR_NODE_NOT_FOUND ||
                                               error->code == ARV_GC_ERROR_ENUM_ENTRY_NOT_FOUND)) {
    kind = Kind::kUnsupported;
  }
  std::string message = fmt::format("{}: {}: {}", uri, operation, error->message ? error->message : "failed");
  if (!advice.empty()) message += "; " + advice;
  throw CameraError(kind, message);
}

std::vector<std::string> device_ids() {
  arv_update_device_list();
  std::vector<std::string> ids;
  const unsigned n = arv_get_n_devices();
  for (unsigned i = 0; i < n; ++i) {
    if (const char* id = arv_get_device_id(i)) ids.emplace_back(id);
  }
  return ids;
}

std::string list_ids(const std::vector<std::string>& ids) {
  return list_camera_uris(
      "aravis", ids,
      "aravis sees no camera (a GigE Vision camera must be on the host's subnet and not "
      "blocked by a firewall; a USB3 Vision one needs the udev rule; `arv-tool-0.8` lists "
      "what aravis sees; see hw/docs/cameras.md)");
}

// `value` rounded to lo + k * step (step 0: continuous); nullopt when it
// lies more than half a step outside [lo, hi].
std::optional<double> to_step(double value, double lo, double hi, double step) {
  const double half = step > 0 ? step / 2 : 0;
  if (!std::isfinite(value) || value < lo - half - 1e-9 || value > hi + half + 1e-9) return std::nullopt;
  if (step > 0) value = lo + std::round((value - lo) / step) * step;
  return std::clamp(value, lo, hi);
}

class AravisCamera final : public camera::Camera {
 public:
  explicit AravisCamera(const camera::CameraUri& uri) : Camera(uri.uri) {
    for (const auto& [key, value] : uri.options) {
      if (key == "trigger_line") {
        if (value.empty())
          fail("camera URI '{}': option trigger_line needs a line name, e.g. Line1", uri.uri);
        trigger_line_ = value;
      } else if (key == "gain_raw_db") {
        gain_raw_db_ = parse_positive(uri, "gain_raw_db", value);
      } else {
        fail("camera URI '{}': unknown option '{}' (aravis: takes trigger_line, gain_raw_db)", uri.uri, key);
      }
    }
    std::string id = uri.target;
    if (id.empty()) {
      const std::vector<std::string> ids = device_ids();
      if (ids.empty())
        throw CameraError(Kind::kNotFound, fmt::format("{}: no camera; {}", uri.uri, list_ids(ids)));
      id = ids.front();
    }
    GErrorHolder error;
    camera_.reset(arv_camera_new(id.c_str(), error.out()));
    if (!camera_) {
      const std::vector<std::string> ids = device_ids();
      const bool listed = std::find(ids.begin(), ids.end(), id) != ids.end();
      const std::string why = error ? error.get()->message : "aravis gave no reason";
      if (!listed) {
        throw CameraError(Kind::kNotFound, fmt::format("{}: no camera with id '{}' ({}); {}", uri.uri, id,
                                                       why, list_ids(ids)));
      }
      // Listed but not opened: someone else holds it, or we may not touch it.
      throw CameraError(Kind::kBusy,
                        fmt::format("{}: cannot open camera '{}': {}; another program may hold it "
                                    "(a USB3 Vision interface claimed, a GigE camera controlled by "
                                    "another host), or the udev rule is missing",
                                    uri.uri, id, why));
    }
    id_ = id;
    ArvDevice* device = arv_camera_get_device(camera_.get());
    if (arv_camera_is_gv_device(camera_.get()) &&
        !arv_gv_device_is_controller(reinterpret_cast<ArvGvDevice*>(device))) {
      throw CameraError(Kind::kBusy,
                        fmt::format("{}: another program or host controls this GigE Vision camera "
                                    "(only one controller at a time); close it and try again",
                                    uri.uri));
    }
    // The heartbeat thread reports a lost camera; wait_frame() raises it.
    control_lost_handler_ = g_signal_connect_data(device, "control-lost",
                                                  reinterpret_cast<GCallback>(&AravisCamera::on_control_lost),
                                                  this, nullptr, GConnectFlags{});
    query();
  }

  ~AravisCamera() override {
    try {
      stop();
    } catch (const std::exception&) {
      // Going away regardless.
    }
    if (control_lost_handler_ != 0)
      g_signal_handler_disconnect(arv_camera_get_device(camera_.get()), control_lost_handler_);
  }

  camera::CameraInfo info() const override {
    return {uri(), model_,
            fmt::format("aravis {}.{}.{} {}", arv_get_major_version(), arv_get_minor_version(),
                        arv_get_micro_version(), protocol_)};
  }
  std::vector<camera::FormatInfo> formats() const override { return formats_; }
  std::vector<camera::TriggerMode> trigger_modes() const override { return trigger_modes_; }
  camera::CameraConfig default_config() const override { return initial_config_; }
  camera::CameraConfig configuration() const override { return config_; }

  camera::Validation validate(camera::CameraConfig& config) const override {
    camera::Validation v;
    // Every format offers the same single range (the Width/Height bounds and increments).
    if (!validate_offered(v, config, formats_, config_.pixel_format, /*name_format=*/false, 64)) return v;
    if (std::find(trigger_modes_.begin(), trigger_modes_.end(), config.trigger) == trigger_modes_.end()) {
      note_invalid(
          v, fmt::format("trigger {} is not offered by this camera ({})", camera::to_string(config.trigger),
                         config.trigger == camera::TriggerMode::kHardware
                             ? fmt::format("its TriggerSource has no {}", trigger_line_)
                             : std::string("its TriggerSource has no Software")));
    }
    return v;
  }

  void configure(const camera::CameraConfig& requested) override {
    const camera::CameraConfig config = require_configurable(*this, requested, streaming_, uri());
    const std::string genicam(genicam_name(config.pixel_format));
    GErrorHolder error;
    arv_camera_set_pixel_format_from_string(camera_.get(), genicam.c_str(), error.out());
    if (error) throw_arv(uri(), fmt::format("set PixelFormat {}", genicam), error.get());

    const bool sensor_roi = config.roi && sensor_window_fits(*config.roi, config.pixel_format);
    const camera::Roi window =
        sensor_roi ? *config.roi : camera::Roi{0, 0, config.size.width, config.size.height};
    set_window(window);

    set_trigger(config.trigger);
    format_ = find_pixel_format(config.pixel_format);
    pixel_format_code_ = arv_camera_get_pixel_format(camera_.get(), error.out());
    if (error) throw_arv(uri(), "read PixelFormat", error.get());
    sensor_roi_ = sensor_roi;
    config_ = config;
    configured_ = true;
  }

  camera::ControlInfo control_info() const override {
    camera::ControlInfo info;
    // A control write reaches the camera before set_controls() returns, but
    // a frame already exposing in free run keeps the old values: one frame.
    // Triggered frames start after the write and are never affected.
    info.latency_frames = 1;
    if (!exposure_feature_.empty()) {
      info.exposure_min_us = exposure_min_;
      info.exposure_max_us = exposure_max_;
      info.exposure_step_us = exposure_step_;
    }
    if (gain_settable()) {
      info.gain_min = db_to_gain(gain_min_db());
      info.gain_max = db_to_gain(gain_max_db());
    }
    return info;
  }

  camera::Controls set_controls(const camera::Controls& controls) override {
    GErrorHolder error;
    if (controls.exposure_us) {
      if (exposure_feature_.empty())
        throw CameraError(Kind::kUnsupported, fmt::format("{}: has no ExposureTime feature", uri()));
      const auto us = to_step(*controls.exposure_us, exposure_min_, exposure_max_, exposure_step_);
      if (!us) {
        throw CameraError(fmt::format("{}: exposure_us {} is outside the camera's range [{}, {}]", uri(),
                                      *controls.exposure_us, exposure_min_, exposure_max_));
      }
      if (has_exposure_auto_) {
        arv_camera_set_exposure_time_auto(camera_.get(), ARV_AUTO_OFF, error.out());
        if (error) throw_arv(uri(), "set ExposureAuto Off", error.get());
      }
      arv_camera_set_float(camera_.get(), exposure_feature_.c_str(), *us, error.out());
      if (error) throw_arv(uri(), fmt::format("set {} {}", exposure_feature_, *us), error.get());
      exposure_us_ = arv_camera_get_float(camera_.get(), exposure_feature_.c_str(), error.out());
      if (error) throw_arv(uri(), fmt::format("read {}", exposure_feature_), error.get());
    }
    if (controls.analogue_gain) {
      const double gain = *controls.analogue_gain;
      if (!gain_settable()) {
        throw CameraError(
            Kind::kUnsupported,
            gain_feature_ == "GainRaw"
                ? fmt::format("{}: the camera has only GainRaw, in its own units; give their size in "
                              "dB as {}?gain_raw_db=STEP (the camera's manual states it)",
                              uri(), uri())
                : fmt::format("{}: has no Gain feature", uri()));
      }
      const double db = gain > 0 ? 20 * std::log10(gain) : -std::numeric_limits<double>::infinity();
      const double step_db = gain_feature_ == "Gain" ? gain_step_ : gain_step_ * gain_raw_db_;
      const auto rounded = to_step(db, gain_min_db(), gain_max_db(), step_db);
      if (!rounded) {
        throw CameraError(fmt::format("{}: analogue_gain {} is outside the camera's range [{}, {}]", uri(),
                                      gain, db_to_gain(gain_min_db()), db_to_gain(gain_max_db())));
      }
      if (has_gain_auto_) {
        arv_camera_set_gain_auto(camera_.get(), ARV_AUTO_OFF, error.out());
        if (error) throw_arv(uri(), "set GainAuto Off", error.get());
      }
      if (gain_feature_ == "Gain") {
        arv_camera_set_float(camera_.get(), "Gain", *rounded, error.out());
        if (error) throw_arv(uri(), fmt::format("set Gain {} dB", *rounded), error.get());
        const double now_db = arv_camera_get_float(camera_.get(), "Gain", error.out());
        if (error) throw_arv(uri(), "read Gain", error.get());
        gain_ = db_to_gain(now_db);
      } else {
        const auto raw = static_cast<gint64>(std::llround(*rounded / gain_raw_db_));
        arv_camera_set_integer(camera_.get(), "GainRaw", raw, error.out());
        if (error) throw_arv(uri(), fmt::format("set GainRaw {}", raw), error.get());
        const gint64 now_raw = arv_camera_get_integer(camera_.get(), "GainRaw", error.out());
        if (error) throw_arv(uri(), "read GainRaw", error.get());
        gain_ = db_to_gain(static_cast<double>(now_raw) * gain_raw_db_);
      }
    }
    return {exposure_us_, gain_};
  }

  void start() override {
    if (streaming_) return;
    if (!configured_) {
      camera::CameraConfig config = config_;
      validate(config);
      configure(config);
    }
    control_lost_ = false;
    GErrorHolder error;
    StreamPtr stream(arv_camera_create_stream(camera_.get(), nullptr, nullptr, error.out()));
    if (!stream) {
      if (error) throw_arv(uri(), "create a stream", error.get());
      throw CameraError(fmt::format("{}: aravis could not create a stream", uri()));
    }
    const guint payload = arv_camera_get_payload(camera_.get(), error.out());
    if (error) throw_arv(uri(), "read PayloadSize", error.get());
    for (int i = 0; i < config_.buffer_count; ++i)
      arv_stream_push_buffer(stream.get(), arv_buffer_new_allocate(payload));
    arv_camera_set_acquisition_mode(camera_.get(), ARV_ACQUISITION_MODE_CONTINUOUS, error.out());
    if (error) throw_arv(uri(), "set AcquisitionMode Continuous", error.get());
    arv_camera_start_acquisition(camera_.get(), error.out());
    if (error) throw_arv(uri(), "start the acquisition", error.get());
    stream_ = std::move(stream);
    streaming_ = true;
    trigger_pending_ = false;
    have_last_id_ = false;
  }

  void stop() override {
    if (!stream_) return;
    streaming_ = false;
    GErrorHolder error;
    arv_camera_stop_acquisition(camera_.get(), error.out());
    stream_.reset();  // joins aravis's stream thread and frees the buffers
    if (error && !control_lost_) throw_arv(uri(), "stop the acquisition", error.get());
  }

  bool streaming() const override { return streaming_; }

  void trigger() override {
    check_software_trigger(config_, streaming_, uri());
    trigger_pending_ = true;
    trigger_time_ns_ = camera::clock_now_ns(camera::ClockDomain::kRealtime);
    GErrorHolder error;
    arv_camera_software_trigger(camera_.get(), error.out());
    if (error) throw_arv(uri(), "send TriggerSoftware", error.get());
  }

  std::optional<camera::Frame> wait_frame(std::chrono::milliseconds timeout) override {
    if (!streaming_)
      throw CameraError(fmt::format("{}: wait_frame() while not streaming; start() first", uri()));
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      if (control_lost_) {
        streaming_ = false;
        throw CameraError(
            Kind::kDisconnected,
            fmt::format("{}: lost control of the camera (unplugged, network down, or another host "
                        "took it)",
                        uri()));
      }
      // Short waits, so that a lost camera is noticed while waiting.
      const auto left =
          std::chrono::duration_cast<std::chrono::microseconds>(deadline - std::chrono::steady_clock::now());
      const auto slice = std::clamp<std::int64_t>(left.count(), 0, 200'000);
      ArvBuffer* buffer = arv_stream_timeout_pop_buffer(stream_.get(), static_cast<guint64>(slice));
      if (!buffer) {
        if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
        continue;
      }
      std::optional<camera::Frame> frame;
      try {
        frame = take_frame(buffer);
      } catch (...) {
        arv_stream_push_buffer(stream_.get(), buffer);
        throw;
      }
      arv_stream_push_buffer(stream_.get(), buffer);
      if (frame) return frame;
    }
  }

 private:
  static void on_control_lost(ArvDevice*, gpointer self) {
    static_cast<AravisCamera*>(self)->control_lost_ = true;
  }

  bool available(const char* feature) const {
    GErrorHolder error;
    const bool yes = arv_camera_is_feature_available(camera_.get(), feature, error.out());
    return yes && !error;
  }

  std::vector<std::string> enumeration(const char* feature) const {
    std::vector<std::string> entries;
    if (!available(feature)) return entries;
    GErrorHolder error;
    guint n = 0;
    const char** values =
        arv_camera_dup_available_enumerations_as_strings(camera_.get(), feature, &n, error.out());
    for (guint i = 0; values && i < n; ++i) entries.emplace_back(values[i]);
    g_free(values);
    return entries;
  }

  static bool contains(const std::vector<std::string>& list, std::string_view entry) {
    return std::find(list.begin(), list.end(), entry) != list.end();
  }

  void query() {
    GErrorHolder error;
    const char* vendor = arv_camera_get_vendor_name(camera_.get(), error.out());
    error.clear();
    const char* model = arv_camera_get_model_name(camera_.get(), error.out());
    error.clear();
    model_ = fmt::format("{}{}{}", vendor ? vendor : "", vendor && model ? " " : "", model ? model : id_);
    protocol_ = arv_camera_is_gv_device(camera_.get())   ? "GigE Vision"
                : arv_camera_is_uv_device(camera_.get()) ? "USB3 Vision"
                                                         : "";

    offsets_ = arv_camera_is_region_offset_available(camera_.get(), error.out()) && !error;
    error.clear();
    if (offsets_) {  // full-size bounds are read with the window at the origin
      int x = 0, y = 0, w = 0, h = 0;
      arv_camera_get_region(camera_.get(), &x, &y, &w, &h, error.out());
      if (!error && (x != 0 || y != 0)) {
        arv_camera_set_region(camera_.get(), 0, 0, w, h, error.out());
        if (error) throw_arv(uri(), "move the region to the origin", error.get());
      }
      error.clear();
      x_step_ = std::max(1, arv_camera_get_x_offset_increment(camera_.get(), error.out()));
      error.clear();
      y_step_ = std::max(1, arv_camera_get_y_offset_increment(camera_.get(), error.out()));
      error.clear();
    }
    arv_camera_get_width_bounds(camera_.get(), &min_size_.width, &max_size_.width, error.out());
    if (error) throw_arv(uri(), "read the Width bounds", error.get());
    arv_camera_get_height_bounds(camera_.get(), &min_size_.height, &max_size_.height, error.out());
    if (error) throw_arv(uri(), "read the Height bounds", error.get());
    width_step_ = std::max(1, arv_camera_get_width_increment(camera_.get(), error.out()));
    error.clear();
    height_step_ = std::max(1, arv_camera_get_height_increment(camera_.get(), error.out()));
    error.clear();

    guint n = 0;
    const char** names = arv_camera_dup_available_pixel_formats_as_strings(camera_.get(), &n, error.out());
    if (error) throw_arv(uri(), "read the PixelFormat entries", error.get());
    std::vector<std::string> offered;
    for (guint i = 0; names && i < n; ++i) {
      offered.emplace_back(names[i]);
      const std::string_view ours = our_name(names[i]);
      const PixelFormatDesc* desc = ours.empty() ? nullptr : find_pixel_format(ours);
      if (!desc) continue;
      camera::FormatInfo info;
      info.pixel_format = std::string(desc->name);
      info.bit_depth = desc->bit_depth;
      info.cfa = desc->cfa;
      info.description = fmt::format("GenICam {}", names[i]);
      info.sizes.push_back({min_size_, max_size_, width_step_, height_step_});
      formats_.push_back(std::move(info));
    }
    g_free(names);
    if (formats_.empty()) {
      std::string text;
      for (const auto& o : offered) text += (text.empty() ? "" : ", ") + o;
      throw CameraError(
          Kind::kUnsupported,
          fmt::format("{}: offers no pixel format Lightstage can unpack (offers: {}; wanted Mono8/10/12/16 "
                      "or Bayer 8/10/12/16, unpacked)",
                      uri(), text.empty() ? "none" : text));
    }

    exposure_feature_ = available("ExposureTime")      ? "ExposureTime"
                        : available("ExposureTimeAbs") ? "ExposureTimeAbs"
                                                       : "";
    if (!exposure_feature_.empty()) {
      arv_camera_get_float_bounds(camera_.get(), exposure_feature_.c_str(), &exposure_min_, &exposure_max_,
                                  error.out());
      if (error) throw_arv(uri(), fmt::format("read the {} bounds", exposure_feature_), error.get());
      exposure_step_ = float_step(exposure_feature_.c_str());
      exposure_us_ = arv_camera_get_float(camera_.get(), exposure_feature_.c_str(), error.out());
      error.clear();
    }
    has_exposure_auto_ = arv_camera_is_exposure_auto_available(camera_.get(), error.out()) && !error;
    error.clear();
    has_gain_auto_ = arv_camera_is_gain_auto_available(camera_.get(), error.out()) && !error;
    error.clear();
    // SFNC: GainSelector picks which gain Gain sets; ours is the analogue one.
    if (const auto selectors = enumeration("GainSelector"); !selectors.empty()) {
      const char* pick = contains(selectors, "AnalogAll") ? "AnalogAll"
                         : contains(selectors, "All")     ? "All"
                                                          : nullptr;
      if (pick) {
        arv_camera_set_string(camera_.get(), "GainSelector", pick, error.out());
        error.clear();
      }
    }
    gain_feature_ = available("Gain") ? "Gain" : available("GainRaw") ? "GainRaw" : "";
    if (gain_feature_ == "Gain") {
      arv_camera_get_float_bounds(camera_.get(), "Gain", &gain_lo_, &gain_hi_, error.out());
      if (error) throw_arv(uri(), "read the Gain bounds", error.get());
      gain_step_ = float_step("Gain");
      gain_ = db_to_gain(arv_camera_get_float(camera_.get(), "Gain", error.out()));
      error.clear();
    } else if (gain_feature_ == "GainRaw") {
      gint64 lo = 0, hi = 0;
      arv_camera_get_integer_bounds(camera_.get(), "GainRaw", &lo, &hi, error.out());
      if (error) throw_arv(uri(), "read the GainRaw bounds", error.get());
      gain_lo_ = static_cast<double>(lo);
      gain_hi_ = static_cast<double>(hi);
      gain_step_ = static_cast<double>(
          std::max<gint64>(1, arv_camera_get_integer_increment(camera_.get(), "GainRaw", error.out())));
      error.clear();
      if (gain_raw_db_ > 0)
        gain_ =
            db_to_gain(static_cast<double>(arv_camera_get_integer(camera_.get(), "GainRaw", error.out())) *
                       gain_raw_db_);
      error.clear();
    }

    trigger_modes_ = {camera::TriggerMode::kFreeRun};
    const auto sources = enumeration("TriggerSource");
    const bool frame_start =
        contains(enumeration("TriggerSelector"), "FrameStart") || !available("TriggerSelector");
    if (frame_start && available("TriggerMode")) {
      if (contains(sources, "Software") && available("TriggerSoftware"))
        trigger_modes_.push_back(camera::TriggerMode::kSoftware);
      if (contains(sources, trigger_line_)) trigger_modes_.push_back(camera::TriggerMode::kHardware);
    }

    // The configuration in force: the camera's format and size when we can deliver them.
    const char* current = arv_camera_get_pixel_format_as_string(camera_.get(), error.out());
    error.clear();
    const std::string_view ours = current ? our_name(current) : std::string_view();
    const bool deliverable = std::any_of(formats_.begin(), formats_.end(),
                                         [&](const camera::FormatInfo& f) { return f.pixel_format == ours; });
    config_.pixel_format = deliverable ? std::string(ours) : formats_.front().pixel_format;
    int x = 0, y = 0, w = 0, h = 0;
    arv_camera_get_region(camera_.get(), &x, &y, &w, &h, error.out());
    config_.size = error ? max_size_ : camera::Size{w, h};
    config_.trigger = camera::TriggerMode::kFreeRun;
    initial_config_ = config_;
  }

  // A float feature's increment, 0 when it has none (aravis then answers the
  // smallest double, or an error).
  double float_step(const char* feature) const {
    GErrorHolder error;
    const double step = arv_camera_get_float_increment(camera_.get(), feature, error.out());
    return error || !(step > 1e-9) || !std::isfinite(step) ? 0.0 : step;
  }

  bool gain_settable() const {
    return gain_feature_ == "Gain" || (gain_feature_ == "GainRaw" && gain_raw_db_ > 0);
  }
  double gain_min_db() const { return gain_feature_ == "Gain" ? gain_lo_ : gain_lo_ * gain_raw_db_; }
  double gain_max_db() const { return gain_feature_ == "Gain" ? gain_hi_ : gain_hi_ * gain_raw_db_; }
  static double db_to_gain(double db) { return std::pow(10.0, db / 20.0); }

  // Whether the camera can window `roi` itself: offsets it allows, a size on
  // its steps, and for Bayer formats even offsets so that the pattern stays.
  bool sensor_window_fits(const camera::Roi& roi, const std::string& pixel_format) const {
    if (!offsets_) return false;
    const PixelFormatDesc* desc = find_pixel_format(pixel_format);
    const bool bayer = desc && desc->cfa != camera::Cfa::kNone;
    if (bayer && (roi.x % 2 != 0 || roi.y % 2 != 0)) return false;
    return roi.x % x_step_ == 0 && roi.y % y_step_ == 0 && roi.width >= min_size_.width &&
           roi.height >= min_size_.height && (roi.width - min_size_.width) % width_step_ == 0 &&
           (roi.height - min_size_.height) % height_step_ == 0;
  }

  void set_window(const camera::Roi& window) {
    GErrorHolder error;
    if (offsets_) {  // offsets first to the origin, so that any width is allowed
      arv_camera_set_integer(camera_.get(), "OffsetX", 0, error.out());
      if (error) throw_arv(uri(), "set OffsetX 0", error.get());
      arv_camera_set_integer(camera_.get(), "OffsetY", 0, error.out());
      if (error) throw_arv(uri(), "set OffsetY 0", error.get());
    }
    arv_camera_set_integer(camera_.get(), "Width", window.width, error.out());
    if (error) throw_arv(uri(), fmt::format("set Width {}", window.width), error.get());
    arv_camera_set_integer(camera_.get(), "Height", window.height, error.out());
    if (error) throw_arv(uri(), fmt::format("set Height {}", window.height), error.get());
    if (offsets_ && window.x != 0) {
      arv_camera_set_integer(camera_.get(), "OffsetX", window.x, error.out());
      if (error) throw_arv(uri(), fmt::format("set OffsetX {}", window.x), error.get());
    }
    if (offsets_ && window.y != 0) {
      arv_camera_set_integer(camera_.get(), "OffsetY", window.y, error.out());
      if (error) throw_arv(uri(), fmt::format("set OffsetY {}", window.y), error.get());
    }
    int x = 0, y = 0, w = 0, h = 0;
    arv_camera_get_region(camera_.get(), &x, &y, &w, &h, error.out());
    if (error) throw_arv(uri(), "read the region", error.get());
    if (x != window.x || y != window.y || w != window.width || h != window.height) {
      throw CameraError(fmt::format("{}: asked for the region {}x{}+{}+{}, the camera set {}x{}+{}+{}", uri(),
                                    window.width, window.height, window.x, window.y, w, h, x, y));
    }
  }

  void set_trigger(camera::TriggerMode mode) {
    GErrorHolder error;
    auto set = [&](const char* feature, const std::string& value) {
      arv_camera_set_string(camera_.get(), feature, value.c_str(), error.out());
      if (error) throw_arv(uri(), fmt::format("set {} {}", feature, value), error.get());
    };
    if (available("TriggerSelector")) set("TriggerSelector", "FrameStart");
    if (mode == camera::TriggerMode::kFreeRun) {
      if (available("TriggerMode")) set("TriggerMode", "Off");
      return;
    }
    set("TriggerSource", mode == camera::TriggerMode::kSoftware ? std::string("Software") : trigger_line_);
    if (mode == camera::TriggerMode::kHardware && contains(enumeration("TriggerActivation"), "RisingEdge"))
      set("TriggerActivation", "RisingEdge");
    set("TriggerMode", "On");
  }

  // The frame in `buffer`, or nullopt when it is to be skipped (a failed
  // transfer, or a frame from before the software trigger).
  std::optional<camera::Frame> take_frame(ArvBuffer* buffer) {
    // Frame ids: 16-bit (wrapping from 65535 to 1) in GigE Vision 1.x, 64-bit
    // in 2.x and USB3 Vision; widen the former across its wrap.
    const std::uint64_t id = arv_buffer_get_frame_id(buffer);
    if (have_last_id_ && id < last_id_) id_offset_ += last_id_;
    last_id_ = id;
    have_last_id_ = true;
    const std::uint64_t sequence = id_offset_ + id;
    if (arv_buffer_get_status(buffer) != ARV_BUFFER_STATUS_SUCCESS)
      return std::nullopt;  // lost: a gap in sequence
    const ArvBufferPayloadType payload = arv_buffer_get_payload_type(buffer);
    if (payload != ARV_BUFFER_PAYLOAD_TYPE_IMAGE && payload != ARV_BUFFER_PAYLOAD_TYPE_EXTENDED_CHUNK_DATA &&
        payload != ARV_BUFFER_PAYLOAD_TYPE_CHUNK_DATA) {
      return std::nullopt;
    }
    const auto timestamp = static_cast<std::int64_t>(arv_buffer_get_system_timestamp(buffer));
    if (config_.trigger == camera::TriggerMode::kSoftware) {
      // The stamp is taken after the exposure, so a frame of this trigger is
      // stamped after it; older ones were waiting in the queue.
      if (!trigger_pending_ || timestamp < trigger_time_ns_) return std::nullopt;
      trigger_pending_ = false;
    }
    camera::CameraConfig delivered = config_;
    if (sensor_roi_) {
      delivered.size = {config_.roi->width, config_.roi->height};
      delivered.roi.reset();
    }
    const int width = arv_buffer_get_image_width(buffer);
    const int height = arv_buffer_get_image_height(buffer);
    if (width != delivered.size.width || height != delivered.size.height ||
        arv_buffer_get_image_pixel_format(buffer) != pixel_format_code_) {
      throw CameraError(fmt::format("{}: frame {} is {}x{} in format 0x{:08x}; configured {}x{} {}", uri(),
                                    sequence, width, height, arv_buffer_get_image_pixel_format(buffer),
                                    delivered.size.width, delivered.size.height, config_.pixel_format));
    }
    gint x_padding = 0, y_padding = 0;
    arv_buffer_get_image_padding(buffer, &x_padding, &y_padding);
    std::size_t size = 0;
    const auto* data = static_cast<const std::uint8_t*>(arv_buffer_get_image_data(buffer, &size));
    const std::size_t stride =
        min_row_bytes(format_->packing, width) + static_cast<std::size_t>(std::max(0, x_padding));
    camera::Frame frame;
    fill_frame_image(frame, {data, data ? size : 0}, delivered, stride, *format_, uri(), sequence);
    frame.sequence = sequence;
    frame.timestamp_ns = timestamp;
    frame.clock = camera::ClockDomain::kRealtime;
    frame.timestamp_point = camera::TimestampPoint::kEndOfFrame;
    frame.exposure_us = exposure_us_;
    frame.analogue_gain = gain_;
    frame.controls_reported = false;
    return frame;
  }

  ArvCameraPtr camera_;
  gulong control_lost_handler_ = 0;
  std::atomic<bool> control_lost_{false};  // set on aravis's heartbeat thread
  std::string id_;
  std::string model_;
  std::string protocol_;
  std::string trigger_line_ = "Line0";
  double gain_raw_db_ = 0;

  std::vector<camera::FormatInfo> formats_;
  std::vector<camera::TriggerMode> trigger_modes_;
  camera::Size min_size_, max_size_;
  int width_step_ = 1, height_step_ = 1, x_step_ = 1, y_step_ = 1;
  bool offsets_ = false;

  std::string exposure_feature_;
  double exposure_min_ = 0, exposure_max_ = 0, exposure_step_ = 0;
  bool has_exposure_auto_ = false;
  std::string gain_feature_;
  double gain_lo_ = 0, gain_hi_ = 0, gain_step_ = 0;  // in the feature's units (dB for Gain)
  bool has_gain_auto_ = false;
  double exposure_us_ = 0;
  double gain_ = 1;

  camera::CameraConfig config_;
  camera::CameraConfig initial_config_;
  bool configured_ = false;
  bool sensor_roi_ = false;
  const PixelFormatDesc* format_ = nullptr;
  ArvPixelFormat pixel_format_code_ = 0;

  StreamPtr stream_;
  bool streaming_ = false;
  bool trigger_pending_ = false;
  std::int64_t trigger_time_ns_ = 0;
  bool have_last_id_ = false;
  std::uint64_t last_id_ = 0;
  std::uint64_t id_offset_ = 0;
};

std::vector<camera::CameraInfo> list_aravis_cameras() {
  arv_update_device_list();
  std::vector<camera::CameraInfo> found;
  const unsigned n = arv_get_n_devices();
  for (unsigned i = 0; i < n; ++i) {
    const char* id = arv_get_device_id(i);
    if (!id) continue;
    const char* vendor = arv_get_device_vendor(i);
    const char* model = arv_get_device_model(i);
    const char* protocol = arv_get_device_protocol(i);
    found.push_back(
        {fmt::format("aravis:{}", id),
         fmt::format("{}{}{}", vendor ? vendor : "", vendor && model ? " " : "", model ? model : ""),
         fmt::format("aravis {}", protocol ? protocol : "")});
  }
  return found;
}

}  // namespace

camera::CameraScheme aravis_camera_scheme() {
  camera::CameraScheme scheme;
  scheme.scheme = "aravis";
  scheme.form = "aravis:DEVICE_ID";
  scheme.open = [](const camera::CameraUri& uri) -> std::unique_ptr<camera::Camera> {
    return std::make_unique<AravisCamera>(uri);
  };
  scheme.list = [] { return list_aravis_cameras(); };
  return scheme;
}

}  // namespace lightstage::hw
