#pragma once
// One camera interface for every backend: v4l2:/dev/videoN and libcamera:ID
// (hw/, opened through hw/cameras.hpp) and sim:PATH (sim/). Callers name a
// camera by URI and never a backend; backends register their URI scheme here
// (register_camera_scheme), so common/ knows none of them.
//
// The life of a camera, in the spirit of libcamera:
//
//   auto cam = open_camera("v4l2:/dev/video0");     // hw::open_camera registers hw's schemes
//   CameraConfig config = cam->default_config();
//   config.pixel_format = "SRGGB12";
//   if (cam->validate(config).status == ConfigStatus::kInvalid) ...   // adjusted in place
//   cam->configure(config);                          // only a Valid configuration is applied
//   cam->set_controls({.exposure_us = 8000, .analogue_gain = 1.0});
//   cam->start();
//   Frame f = cam->capture(std::chrono::milliseconds(500));   // throws CameraError on timeout
//   cam->stop();
//
// Frames are values: the image is copied out of the driver's buffer before the
// buffer goes back to the device. Raw (Bayer) images stay mosaicked; the frame
// records the colour-filter pattern of its top-left pixel.
//
// Threading: a Camera is used from one thread at a time.

#include "lightstage/common/error.hpp"

#include <opencv2/core/mat.hpp>

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace lightstage::camera {

// ---------------------------------------------------------------------------
// Errors

// Every camera failure. The message names the camera URI and what failed;
// kind() lets a capture session tell a lost frame (retake) from a lost camera.
class CameraError : public Error {
 public:
  enum class Kind {
    kFailed,        // an operation the device refused (the message says which and why)
    kTimeout,       // no frame within the time asked for
    kDisconnected,  // the device went away (unplugged, driver unbound, ENODEV)
    kBusy,          // another process holds the camera
    kNotFound,      // no such device / camera id
    kUnsupported,   // this camera cannot do what was asked
  };
  CameraError(Kind kind, const std::string& message) : Error(message), kind_(kind) {}
  explicit CameraError(const std::string& message) : CameraError(Kind::kFailed, message) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

std::string_view to_string(CameraError::Kind kind);

// ---------------------------------------------------------------------------
// Clocks

// The clock a timestamp was read from. V4L2 buffers carry CLOCK_MONOTONIC (when
// the driver sets V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC); libcamera documents its
// SensorTimestamp as CLOCK_BOOTTIME; libgpiod edge events are CLOCK_MONOTONIC.
// MONOTONIC and BOOTTIME differ by the time the system spent suspended.
enum class ClockDomain { kMonotonic, kBoottime, kRealtime, kUnknown };

std::string_view to_string(ClockDomain domain);

// Now, in nanoseconds, on `domain`'s clock. Throws CameraError for Unknown.
std::int64_t clock_now_ns(ClockDomain domain);

// What to add to a time on `from` to express it on `to`, measured now by
// reading the clocks back to back (the tightest of a few bracketed readings;
// error well under a microsecond). Throws CameraError when either is Unknown.
std::int64_t clock_offset_ns(ClockDomain from, ClockDomain to);

// `t_ns` on `from`, expressed on `to` (identity when from == to).
std::int64_t convert_timestamp_ns(std::int64_t t_ns, ClockDomain from, ClockDomain to);

// ---------------------------------------------------------------------------
// Formats

struct Size {
  int width = 0;
  int height = 0;
  bool operator==(const Size&) const = default;
};

// A region of interest in image pixels: x, y of the top-left corner.
struct Roi {
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;
  bool operator==(const Roi&) const = default;
};

// The colour filter over the top-left 2x2 pixels of a raw image, read row by
// row ("RGGB": R at (0,0), G at (0,1), G at (1,0), B at (1,1)); None for
// monochrome and for already-demosaicked images.
enum class Cfa { kNone, kRGGB, kBGGR, kGRBG, kGBRG };

std::string_view to_string(Cfa cfa);

// The pattern at the top-left of a crop that starts at (x, y) of an image with
// pattern `cfa` (odd offsets swap columns / rows).
Cfa cfa_at(Cfa cfa, int x, int y);

// A pixel format as the backends name it (V4L2-style names, one spelling for
// all backends): "GREY", "Y10", "Y12", "Y16", "YUYV", "SRGGB8", "SBGGR12",
// "SRGGB10P" (MIPI CSI-2 packed), ... bit_depth is the number of significant
// bits in the delivered image (8-bit images are CV_8UC1, deeper ones CV_16UC1
// with values in [0, 2^bit_depth - 1], not scaled up).
struct FormatInfo {
  std::string pixel_format;
  int bit_depth = 8;
  Cfa cfa = Cfa::kNone;
  std::string description;  // e.g. "12-bit Bayer RGGB, unpacked" or the driver's text
  // Frame sizes: each entry a range [min, max] in steps; a discrete size has
  // min == max.
  struct SizeRange {
    Size min;
    Size max;
    int step_width = 1;
    int step_height = 1;
  };
  std::vector<SizeRange> sizes;
};

enum class TriggerMode {
  kFreeRun,   // the sensor streams at its own rate; every frame is delivered
  kSoftware,  // trigger() starts an exposure; the first frame exposed wholly after it is delivered
  kHardware,  // the sensor exposes on an edge of its trigger input (wired to the controller)
};

std::string_view to_string(TriggerMode mode);

// The stream configuration. Zero / empty fields mean "the camera's choice".
struct CameraConfig {
  std::string pixel_format;
  Size size;
  std::optional<Roi> roi;  // a crop of `size`; frames are roi-sized
  int buffer_count = 4;
  TriggerMode trigger = TriggerMode::kFreeRun;
};

enum class ConfigStatus { kValid, kAdjusted, kInvalid };

std::string_view to_string(ConfigStatus status);

struct Validation {
  ConfigStatus status = ConfigStatus::kValid;
  std::vector<std::string> notes;  // one line per adjustment or problem, naming field and value
  std::string message() const;     // the notes joined with "; "
};

// ---------------------------------------------------------------------------
// Controls

// Manual controls. Unset fields are left as they are.
struct Controls {
  std::optional<double> exposure_us = std::nullopt;
  std::optional<double> analogue_gain = std::nullopt;  // a multiplier, 1.0 = unity
};

struct ControlInfo {
  double exposure_min_us = 0;
  double exposure_max_us = 0;
  double exposure_step_us = 0;  // 0: continuous
  double gain_min = 1;
  double gain_max = 1;
  // Frames a control change may take to reach the sensor when the backend
  // cannot tell per frame (V4L2): a capture session drops this many after a
  // change. 0 when frames report the values actually applied (libcamera with an IPA).
  int latency_frames = 0;
};

// ---------------------------------------------------------------------------
// Frames

// Where in the frame's life its timestamp was taken.
enum class TimestampPoint { kStartOfExposure, kEndOfFrame, kUnknown };

std::string_view to_string(TimestampPoint point);

struct Frame {
  cv::Mat image;  // CV_8UC1 or CV_16UC1 (file cameras: also CV_16UC3, BGR), owned by the frame
  std::string pixel_format;
  int bit_depth = 8;
  Cfa cfa = Cfa::kNone;
  std::uint64_t sequence = 0;  // the device's frame counter; a gap means frames were lost
  std::int64_t timestamp_ns = 0;
  ClockDomain clock = ClockDomain::kUnknown;
  TimestampPoint timestamp_point = TimestampPoint::kUnknown;
  double exposure_us = 0;
  double analogue_gain = 1;
  // True when the device reported exposure and gain for this very frame;
  // false when they are the values last set (see ControlInfo::latency_frames).
  bool controls_reported = false;
  // Stills cameras whose shots arrive as files (shot_source.hpp): the stamp is
  // the camera's own clock (EXIF, clock kRealtime read as UTC), off the
  // host's by an unknown amount, in steps of timestamp_resolution_ns (1 ms
  // with sub-second EXIF, 1 s without, 0 = no stamp); arrived_ns is
  // CLOCK_MONOTONIC when the file arrived; source_file the file itself.
  bool own_clock = false;
  std::int64_t timestamp_resolution_ns = 0;
  std::int64_t arrived_ns = 0;
  std::string source_file;
};

// Crops `frame` to `roi` (bounds checked; names `uri` in the error) and keeps
// the CFA pattern right for odd offsets. The image is not copied.
void crop_frame(Frame& frame, const Roi& roi, const std::string& uri);

// ---------------------------------------------------------------------------
// The camera

struct CameraInfo {
  std::string uri;
  std::string model;   // sensor or card name
  std::string driver;  // kernel driver or pipeline handler, when known
};

class Camera {
 public:
  virtual ~Camera() = default;
  Camera(const Camera&) = delete;
  Camera& operator=(const Camera&) = delete;

  const std::string& uri() const { return uri_; }
  virtual CameraInfo info() const = 0;

  virtual std::vector<FormatInfo> formats() const = 0;
  virtual std::vector<TriggerMode> trigger_modes() const = 0;

  // A configuration the camera would accept as it is (its default format and size).
  virtual CameraConfig default_config() const = 0;
  // Checks `config`, changing fields the camera cannot honour to the nearest it
  // can (status Adjusted, a note per change) or reporting what is impossible
  // (Invalid). Touches no device state.
  virtual Validation validate(CameraConfig& config) const = 0;
  // Applies a configuration that validates as Valid; throws CameraError
  // (naming the field and value) for anything else, or when streaming.
  virtual void configure(const CameraConfig& config) = 0;
  // The configuration in force (default_config() before configure()).
  virtual CameraConfig configuration() const = 0;

  virtual ControlInfo control_info() const = 0;
  // Switches to manual exposure and gain and sets the given ones. Values are
  // rounded to the device's step; out-of-range values throw CameraError naming
  // the value and the range. Returns the values now in force.
  virtual Controls set_controls(const Controls& controls) = 0;

  virtual void start() = 0;
  virtual void stop() = 0;  // idempotent
  virtual bool streaming() const = 0;

  // Software trigger mode: starts an exposure. Throws CameraError in other modes.
  virtual void trigger() = 0;

  // The next frame, or nullopt when none arrives within `timeout` (in Hardware
  // trigger mode that is normal between triggers). Throws CameraError when not
  // streaming or when the device fails (Kind::kDisconnected when it went away).
  virtual std::optional<Frame> wait_frame(std::chrono::milliseconds timeout) = 0;

  // wait_frame, with a timeout being an error (Kind::kTimeout, naming the URI).
  Frame capture(std::chrono::milliseconds timeout);

 protected:
  explicit Camera(std::string uri) : uri_(std::move(uri)) {}

 private:
  std::string uri_;
};

// ---------------------------------------------------------------------------
// Opening by URI

// "scheme:rest" split at the first colon ("libcamera:" ids may hold colons).
struct CameraUri {
  std::string uri;                                           // as given
  std::string scheme;                                        // "v4l2"
  std::string target;                                        // "/dev/video0" (the part before any '?')
  std::vector<std::pair<std::string, std::string>> options;  // "?key=value&key2=value2"
  // The value of option `key`, if given.
  std::optional<std::string> option(std::string_view key) const;
};

// Parses `uri`; throws InputError naming it when it has no scheme.
CameraUri parse_camera_uri(const std::string& uri);

struct CameraScheme {
  std::string scheme;       // "v4l2"
  std::string form;         // "v4l2:/dev/videoN" (shown in errors and help)
  std::string unavailable;  // non-empty: this build cannot open it, and why
  std::function<std::unique_ptr<Camera>(const CameraUri&)> open;
  // The URIs of the cameras this machine can see (may be empty or null).
  std::function<std::vector<CameraInfo>()> list;
};

// Adds (or replaces) a scheme. Thread-safe; backends call it from a register
// function (hw::register_hw_cameras, sim::register_sim_camera) -- not from a
// static initialiser, which a static library would drop.
void register_camera_scheme(CameraScheme scheme);
std::vector<CameraScheme> camera_schemes();

// Opens the camera named by `uri` through its registered scheme. Throws
// InputError for a malformed URI or an unknown scheme (listing the known
// ones), CameraError from the backend (naming the URI).
std::unique_ptr<Camera> open_camera_uri(const std::string& uri);

}  // namespace lightstage::camera
