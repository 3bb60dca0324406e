#include "lightstage/host/capture/file_camera.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/capture/folder_source.hpp"
#include "lightstage/host/io/exif.hpp"
#include "lightstage/host/io/image_io.hpp"

#ifdef LIGHTSTAGE_HAVE_GPHOTO2
#include "lightstage/hw/gphoto2_source.hpp"
#endif

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <mutex>

namespace lightstage {
namespace {

using camera::CameraError;

std::string config_text(camera::TriggerMode mode) {
  return mode == camera::TriggerMode::kHardware ? "its remote port (the rig's trigger) only" : "USB only";
}

constexpr char kFormat[] = "FILE";

class FileCamera final : public camera::Camera {
 public:
  FileCamera(std::unique_ptr<camera::ShotSource> source, FileCameraOptions options)
      : Camera(source->uri()), source_(std::move(source)), options_(options) {
    config_ = default_config();
  }
  ~FileCamera() override { stop(); }

  camera::CameraInfo info() const override { return source_->info(); }

  std::vector<camera::FormatInfo> formats() const override {
    camera::FormatInfo format;
    format.pixel_format = kFormat;
    format.bit_depth = 16;
    format.description = fmt::format("the camera's files decoded linear (RAW at {} size, TIFF, JPEG/PNG)",
                                     options_.demosaic == io::RawDemosaic::half ? "half" : "full");
    return {format};
  }

  std::vector<camera::TriggerMode> trigger_modes() const override {
    if (options_.remote_port || !source_->software_trigger()) return {camera::TriggerMode::kHardware};
    return {camera::TriggerMode::kSoftware};
  }

  camera::CameraConfig default_config() const override {
    camera::CameraConfig config;
    config.pixel_format = kFormat;
    config.trigger = trigger_modes().front();
    return config;
  }

  camera::Validation validate(camera::CameraConfig& config) const override {
    camera::Validation v;
    const auto adjust = [&](std::string note) {
      if (v.status == camera::ConfigStatus::kValid) v.status = camera::ConfigStatus::kAdjusted;
      v.notes.push_back(std::move(note));
    };
    if (config.pixel_format != kFormat) {
      adjust(fmt::format("pixel_format '{}' -> '{}' (the camera's own files)", config.pixel_format, kFormat));
      config.pixel_format = kFormat;
    }
    if (config.size != camera::Size{}) {
      adjust(fmt::format("size {}x{} -> the files' own", config.size.width, config.size.height));
      config.size = {};
    }
    if (std::ranges::count(trigger_modes(), config.trigger) == 0) {
      v.status = camera::ConfigStatus::kInvalid;
      v.notes.push_back(fmt::format("trigger {}: {} is fired by {}", camera::to_string(config.trigger), uri(),
                                    config_text(trigger_modes().front())));
    }
    return v;
  }

  void configure(const camera::CameraConfig& config) override {
    if (streaming_) throw CameraError(uri() + ": configure while capturing");
    camera::CameraConfig checked = config;
    const camera::Validation v = validate(checked);
    if (v.status != camera::ConfigStatus::kValid)
      throw CameraError(camera::CameraError::Kind::kUnsupported, uri() + ": " + v.message());
    config_ = config;
  }
  camera::CameraConfig configuration() const override { return config_; }

  camera::ControlInfo control_info() const override {
    camera::ControlInfo info;
    info.exposure_min_us = 125;         // 1/8000 s, the fastest focal-plane shutters
    info.exposure_max_us = 30'000'000;  // 30 s, the longest timed speed
    info.gain_min = 0.5;                // ISO 50 ..
    info.gain_max = 1024;               // .. ISO 102400
    return info;
  }

  camera::Controls set_controls(const camera::Controls& controls) override {
    camera::ShotSettings wanted;
    wanted.exposure_us = controls.exposure_us;
    if (controls.analogue_gain) wanted.iso = *controls.analogue_gain * 100;
    const camera::ShotSettings now = source_->apply(wanted);
    if (controls.exposure_us) expected_exposure_us_ = now.exposure_us.value_or(*controls.exposure_us);
    if (controls.analogue_gain) gain_ = now.iso ? *now.iso / 100 : *controls.analogue_gain;
    return {expected_exposure_us_ > 0 ? std::optional(expected_exposure_us_) : std::nullopt, gain_};
  }

  void start() override {
    if (streaming_) return;
    const camera::ShotSettings& wanted = options_.settings;
    if (wanted.f_number || wanted.iso || wanted.image_format) {
      const camera::ShotSettings now = source_->apply(wanted);
      logger("capture")->info("{}: set to aperture f/{}, ISO {}, format {}", uri(),
                              now.f_number ? fmt::format("{:g}", *now.f_number) : "?",
                              now.iso ? fmt::format("{:g}", *now.iso) : "?", now.image_format.value_or("?"));
      if (now.iso) gain_ = *now.iso / 100;
    }
    source_->start();
    streaming_ = true;
  }
  void stop() override {
    if (!streaming_) return;
    streaming_ = false;
    try {
      source_->stop();
    } catch (const std::exception& e) {
      logger("capture")->warn("{}: {}", uri(), e.what());
    }
  }
  bool streaming() const override { return streaming_; }

  void trigger() override {
    if (config_.trigger != camera::TriggerMode::kSoftware)
      throw CameraError(uri() + ": trigger() in " + std::string(camera::to_string(config_.trigger)) +
                        " mode");
    source_->trigger();
  }

  std::optional<camera::Frame> wait_frame(std::chrono::milliseconds timeout) override {
    if (!streaming_) throw CameraError(uri() + ": wait_frame while not capturing");
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      auto file = source_->wait_file(std::max(left, std::chrono::milliseconds(0)));
      if (!file) return std::nullopt;
      try {
        return decode(*file);
      } catch (const InputError& e) {
        // A damaged or foreign file: its step gets no frame and is taken again.
        logger("capture")->warn("{}: skipped: {}", uri(), e.what());
      }
    }
  }

 private:
  camera::Frame decode(const camera::ArrivedFile& file) {
    const bool raw = io::is_raw_file(file.path);
    // RAW + JPEG: two files per shot, which no matching can tell apart.
    if (!first_file_.empty() && raw != io::is_raw_file(first_file_)) {
      throw CameraError(
          fmt::format("{}: {} and {} are one RAW and one other file: set the camera to RAW only "
                      "(RAW + JPEG gives two files per shot)",
                      uri(), first_file_.string(), file.path.string()));
    }
    camera::Frame frame;
    frame.image = raw ? io::read_raw(file.path, options_.demosaic).image : io::read_image(file.path);
    if (frame.image.depth() != CV_8U && frame.image.depth() != CV_16U)
      fail("{}: {} holds floating-point samples; a camera file is 8 or 16 bits", uri(), file.path.string());
    frame.bit_depth = frame.image.depth() == CV_8U ? 8 : 16;
    frame.pixel_format = fmt::format("{}{}", frame.image.channels() == 3 ? "BGR" : "Y",
                                     frame.bit_depth * frame.image.channels());
    if (first_file_.empty()) {
      first_file_ = file.path;
      first_size_ = frame.image.size();
    }
    if (frame.image.size() != first_size_) {
      throw CameraError(fmt::format(
          "{}: {} is {}x{}, the camera's earlier files {}x{} (was its image size changed?)", uri(),
          file.path.string(), frame.image.cols, frame.image.rows, first_size_.width, first_size_.height));
    }
    frame.sequence = sequence_++;
    frame.clock = camera::ClockDomain::kRealtime;
    frame.timestamp_point = camera::TimestampPoint::kStartOfExposure;
    frame.own_clock = true;
    frame.arrived_ns = file.arrived_ns;
    frame.source_file = file.path.string();
    frame.exposure_us = expected_exposure_us_;
    frame.analogue_gain = gain_;
    io::ExifInfo exif;
    try {
      exif = io::read_exif(file.path);
    } catch (const InputError& e) {
      logger("capture")->warn("{}: {}: no EXIF ({}); matched by arrival only", uri(), file.path.string(),
                              e.what());
    }
    if (const auto taken = io::taken_time(exif)) {
      frame.timestamp_ns = taken->ns;
      frame.timestamp_resolution_ns = taken->resolution_ns;
    }
    // What the camera says it did; the capture checks it against what its step asked.
    if (exif.exposure_s && *exif.exposure_s > 0) {
      frame.exposure_us = *exif.exposure_s * 1e6;
      frame.controls_reported = true;
    }
    if (exif.iso && *exif.iso > 0) frame.analogue_gain = *exif.iso / 100;
    if (config_.roi) camera::crop_frame(frame, *config_.roi, uri());
    return frame;
  }

  std::unique_ptr<camera::ShotSource> source_;
  FileCameraOptions options_;
  camera::CameraConfig config_;
  bool streaming_ = false;
  double expected_exposure_us_ = 0;
  double gain_ = 1;
  std::filesystem::path first_file_;  // the first file decoded, and its size: every file must match
  cv::Size first_size_;
  std::uint64_t sequence_ = 0;
};

// The camera's options (demosaic=half|full; gphoto2: fire=usb|remote) and
// the URI without them, for the source.
std::pair<FileCameraOptions, camera::CameraUri> file_camera_options(camera::CameraUri uri, bool remote_port) {
  FileCameraOptions options;
  options.remote_port = remote_port;
  if (const auto word = uri.option("demosaic"))
    options.demosaic = io::parse_raw_demosaic(*word, uri.uri + ": demosaic");
  if (const auto fire = uri.option("fire")) {
    if (*fire != "usb" && *fire != "remote")
      fail(
          "{}: fire must be usb (the camera is fired over USB) or remote (by the rig's trigger on its remote "
          "port), got '{}'",
          uri.uri, *fire);
    options.remote_port = *fire == "remote";
  }
  // What the camera is set to for the whole capture (the shutter speed follows the capture's exposure).
  const auto positive = [&](const char* key) -> std::optional<double> {
    const auto text = uri.option(key);
    if (!text) return std::nullopt;
    char* end = nullptr;
    const double value = std::strtod(text->c_str(), &end);
    if (end == text->c_str() || *end != '\0' || !(value > 0) || !std::isfinite(value))
      fail("{}: {} must be a positive number, got '{}'", uri.uri, key, *text);
    return value;
  };
  options.settings.f_number = positive("aperture");
  options.settings.iso = positive("iso");
  if (const auto format = uri.option("format")) options.settings.image_format = *format;
  std::erase_if(uri.options, [](const auto& o) {
    return o.first == "demosaic" || o.first == "fire" || o.first == "aperture" || o.first == "iso" ||
           o.first == "format";
  });
  return {options, std::move(uri)};
}

}  // namespace

std::unique_ptr<camera::Camera> make_file_camera(std::unique_ptr<camera::ShotSource> source,
                                                 FileCameraOptions options) {
  return std::make_unique<FileCamera>(std::move(source), options);
}

namespace {

std::unique_ptr<camera::Camera> open_folder_camera(const camera::CameraUri& uri) {
  if (uri.option("fire")) fail("{}: a folder's camera is fired by its remote port only", uri.uri);
  for (const char* key : {"aperture", "iso", "format"}) {
    if (uri.option(key)) fail("{}: {}: a folder's camera is set by hand, not through the URI", uri.uri, key);
  }
  auto [options, rest] = file_camera_options(uri, true);
  return make_file_camera(open_folder_source(rest), options);
}

#ifdef LIGHTSTAGE_HAVE_GPHOTO2
std::unique_ptr<camera::Camera> open_gphoto2_camera(const camera::CameraUri& uri) {
  auto [options, rest] = file_camera_options(uri, false);
  // The originals are kept: downloads go to a folder of their own in the working directory.
  const std::filesystem::path download = "lightstage-shots";
  if (!rest.option("download")) std::filesystem::create_directories(download);
  return make_file_camera(hw::open_gphoto2_source(rest, download), options);
}
#endif

}  // namespace

void register_file_cameras() {
  static std::once_flag once;
  std::call_once(once, [] {
    camera::register_camera_scheme({"folder", "folder:PATH", "", open_folder_camera, {}});
#ifdef LIGHTSTAGE_HAVE_GPHOTO2
    camera::register_camera_scheme({"gphoto2", "gphoto2:[MODEL|PORT]", "", open_gphoto2_camera,
                                    [] { return hw::list_gphoto2_cameras(); }});
#else
    camera::register_camera_scheme({"gphoto2", "gphoto2:[MODEL|PORT]",
                                    "this build has no gphoto2 backend (install libgphoto2-dev and rebuild)",
                                    {},
                                    {}});
#endif
  });
}

}  // namespace lightstage
