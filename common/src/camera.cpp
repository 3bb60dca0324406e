#include "lightstage/common/camera.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <ctime>
#include <limits>
#include <mutex>

namespace lightstage::camera {

std::string_view to_string(CameraError::Kind kind) {
  switch (kind) {
    case CameraError::Kind::kFailed:
      return "failed";
    case CameraError::Kind::kTimeout:
      return "timeout";
    case CameraError::Kind::kDisconnected:
      return "disconnected";
    case CameraError::Kind::kBusy:
      return "busy";
    case CameraError::Kind::kNotFound:
      return "not found";
    case CameraError::Kind::kUnsupported:
      return "unsupported";
  }
  return "?";
}

std::string_view to_string(ClockDomain domain) {
  switch (domain) {
    case ClockDomain::kMonotonic:
      return "CLOCK_MONOTONIC";
    case ClockDomain::kBoottime:
      return "CLOCK_BOOTTIME";
    case ClockDomain::kRealtime:
      return "CLOCK_REALTIME";
    case ClockDomain::kUnknown:
      return "unknown clock";
  }
  return "?";
}

std::string_view to_string(Cfa cfa) {
  switch (cfa) {
    case Cfa::kNone:
      return "none";
    case Cfa::kRGGB:
      return "RGGB";
    case Cfa::kBGGR:
      return "BGGR";
    case Cfa::kGRBG:
      return "GRBG";
    case Cfa::kGBRG:
      return "GBRG";
  }
  return "?";
}

std::string_view to_string(TriggerMode mode) {
  switch (mode) {
    case TriggerMode::kFreeRun:
      return "free-run";
    case TriggerMode::kSoftware:
      return "software";
    case TriggerMode::kHardware:
      return "hardware";
  }
  return "?";
}

std::string_view to_string(ConfigStatus status) {
  switch (status) {
    case ConfigStatus::kValid:
      return "valid";
    case ConfigStatus::kAdjusted:
      return "adjusted";
    case ConfigStatus::kInvalid:
      return "invalid";
  }
  return "?";
}

std::string_view to_string(TimestampPoint point) {
  switch (point) {
    case TimestampPoint::kStartOfExposure:
      return "start of exposure";
    case TimestampPoint::kEndOfFrame:
      return "end of frame";
    case TimestampPoint::kUnknown:
      return "unknown";
  }
  return "?";
}

// --- clocks ------------------------------------------------------------------

namespace {

clockid_t clock_id(ClockDomain domain) {
  switch (domain) {
    case ClockDomain::kMonotonic:
      return CLOCK_MONOTONIC;
    case ClockDomain::kBoottime:
      return CLOCK_BOOTTIME;
    case ClockDomain::kRealtime:
      return CLOCK_REALTIME;
    case ClockDomain::kUnknown:
      break;
  }
  throw CameraError(CameraError::Kind::kUnsupported,
                    "cannot read the clock of a timestamp whose clock is unknown");
}

std::int64_t read_ns(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace

std::int64_t clock_now_ns(ClockDomain domain) { return read_ns(clock_id(domain)); }

std::int64_t clock_offset_ns(ClockDomain from, ClockDomain to) {
  const clockid_t from_id = clock_id(from);
  const clockid_t to_id = clock_id(to);
  if (from == to) return 0;
  // to, from, to: the from-reading lies between the two to-readings; the
  // tightest bracket of a few tries bounds the error by half its width.
  std::int64_t best_width = std::numeric_limits<std::int64_t>::max();
  std::int64_t best_offset = 0;
  for (int i = 0; i < 5; ++i) {
    const std::int64_t t0 = read_ns(to_id);
    const std::int64_t f = read_ns(from_id);
    const std::int64_t t1 = read_ns(to_id);
    if (t1 - t0 < best_width) {
      best_width = t1 - t0;
      best_offset = t0 + (t1 - t0) / 2 - f;
    }
  }
  return best_offset;
}

std::int64_t convert_timestamp_ns(std::int64_t t_ns, ClockDomain from, ClockDomain to) {
  if (from == to) return t_ns;
  return t_ns + clock_offset_ns(from, to);
}

// --- formats and frames ---------------------------------------------------------

Cfa cfa_at(Cfa cfa, int x, int y) {
  if (cfa == Cfa::kNone) return cfa;
  // The 2x2 pattern as [row][col] letters; the crop's top-left is at (y&1, x&1).
  const std::string_view name = to_string(cfa);
  const char grid[2][2] = {{name[0], name[1]}, {name[2], name[3]}};
  const int r = y & 1;
  const int c = x & 1;
  const std::string shifted{grid[r][c], grid[r][c ^ 1], grid[r ^ 1][c], grid[r ^ 1][c ^ 1]};
  for (Cfa candidate : {Cfa::kRGGB, Cfa::kBGGR, Cfa::kGRBG, Cfa::kGBRG}) {
    if (to_string(candidate) == shifted) return candidate;
  }
  return cfa;  // unreachable: every shift of a Bayer pattern is a Bayer pattern
}

void crop_frame(Frame& frame, const Roi& roi, const std::string& uri) {
  if (roi.x < 0 || roi.y < 0 || roi.width <= 0 || roi.height <= 0 || roi.x + roi.width > frame.image.cols ||
      roi.y + roi.height > frame.image.rows) {
    throw CameraError(CameraError::Kind::kFailed,
                      fmt::format("{}: roi {}x{}+{}+{} does not fit in the {}x{} frame", uri, roi.width,
                                  roi.height, roi.x, roi.y, frame.image.cols, frame.image.rows));
  }
  frame.image = frame.image(cv::Rect(roi.x, roi.y, roi.width, roi.height));
  frame.cfa = cfa_at(frame.cfa, roi.x, roi.y);
}

std::string Validation::message() const {
  std::string out;
  for (const auto& note : notes) out += (out.empty() ? "" : "; ") + note;
  return out;
}

Frame Camera::capture(std::chrono::milliseconds timeout) {
  if (auto frame = wait_frame(timeout)) return std::move(*frame);
  throw CameraError(CameraError::Kind::kTimeout,
                    fmt::format("{}: no frame within {} ms", uri(), timeout.count()));
}

// --- URIs and the scheme registry -----------------------------------------------

std::optional<std::string> CameraUri::option(std::string_view key) const {
  for (const auto& [k, v] : options) {
    if (k == key) return v;
  }
  return std::nullopt;
}

CameraUri parse_camera_uri(const std::string& uri) {
  const auto colon = uri.find(':');
  if (colon == std::string::npos || colon == 0) {
    fail("'{}' is not a camera URI (expected scheme:target, e.g. v4l2:/dev/video0, libcamera:ID, sim:PATH)",
         uri);
  }
  CameraUri parsed;
  parsed.uri = uri;
  parsed.scheme = uri.substr(0, colon);
  for (char c : parsed.scheme) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) {
      fail("camera URI '{}': bad scheme '{}' (letters and digits only)", uri, parsed.scheme);
    }
  }
  std::string rest = uri.substr(colon + 1);
  const auto query = rest.find('?');
  if (query != std::string::npos) {
    std::string_view options = std::string_view(rest).substr(query + 1);
    while (!options.empty()) {
      const auto amp = options.find('&');
      const std::string_view item = options.substr(0, amp);
      const auto eq = item.find('=');
      if (eq == std::string_view::npos || eq == 0) {
        fail("camera URI '{}': option '{}' is not key=value", uri, std::string(item));
      }
      parsed.options.emplace_back(std::string(item.substr(0, eq)), std::string(item.substr(eq + 1)));
      options = amp == std::string_view::npos ? std::string_view() : options.substr(amp + 1);
    }
    rest.resize(query);
  }
  parsed.target = rest;
  return parsed;
}

namespace {

struct Registry {
  std::mutex mutex;
  std::vector<CameraScheme> schemes;
};

Registry& registry() {
  static Registry instance;
  return instance;
}

std::string list_forms(const std::vector<CameraScheme>& schemes) {
  std::string list;
  for (const auto& scheme : schemes) {
    list += (list.empty() ? "" : ", ") + scheme.form;
    if (!scheme.unavailable.empty()) list += " (not in this build)";
  }
  return list.empty() ? "none registered" : list;
}

}  // namespace

void register_camera_scheme(CameraScheme scheme) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  for (auto& existing : r.schemes) {
    if (existing.scheme == scheme.scheme) {
      existing = std::move(scheme);
      return;
    }
  }
  r.schemes.push_back(std::move(scheme));
}

std::vector<CameraScheme> camera_schemes() {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  return r.schemes;
}

std::unique_ptr<Camera> open_camera_uri(const std::string& uri) {
  const CameraUri parsed = parse_camera_uri(uri);
  const std::vector<CameraScheme> schemes = camera_schemes();
  const auto it = std::find_if(schemes.begin(), schemes.end(),
                               [&](const CameraScheme& s) { return s.scheme == parsed.scheme; });
  if (it == schemes.end()) {
    fail("camera URI '{}': unknown scheme '{}' (expected one of: {})", uri, parsed.scheme,
         list_forms(schemes));
  }
  if (!it->unavailable.empty()) {
    throw CameraError(CameraError::Kind::kUnsupported, fmt::format("{}: {}", uri, it->unavailable));
  }
  if (!it->open)
    throw CameraError(CameraError::Kind::kUnsupported, fmt::format("{}: scheme has no opener", uri));
  return it->open(parsed);
}

}  // namespace lightstage::camera
