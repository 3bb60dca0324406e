#pragma once
// What the page asks of the station, read from its JSON bodies. Every field
// is checked: a missing, mistyped or out-of-range one is refused (400) with
// a message naming it; unknown fields too, so a typo never passes silently.

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace lightstage::station {

// A folder name under the station's data folder: letters, digits, '.', '_',
// '-'; not starting with '.'; at most 64 characters. Throws Refused(400) naming `field`.
void check_folder_name(const std::string& name, const std::string& field);

struct LedsRequest {
  std::vector<std::pair<std::uint32_t, float>> levels;  // empty = dark
};

struct PreviewRequest {
  std::uint32_t led = 0;
  double exposure_us = 0;
  std::optional<double> gain;
};

// The test sequence: every LED alone in turn, each lit this long (slow
// enough to watch each one, or fast to check the timing).
struct TestSequenceRequest {
  std::uint32_t on_us = 10'000;
};

struct CaptureRequest {
  std::string name;                   // DATA/stacks/NAME
  std::optional<double> exposure_us;  // unset = automatic per LED
  int dark_frames = 4;
  std::vector<double> bracket_stops;
  std::vector<int> led_ids;  // empty = every LED
  // A chrome sphere's highlight is a few pixels, too few for the automatic
  // exposure's percentile: each LED is then exposed for its brightest pixel.
  bool chrome_sphere = false;
  nlohmann::json to_json() const;
};

// A chrome sphere's outline as the operator drew it on a stack's picture
// (image pixels, pixel (c, r) centred at (c + 0.5, r + 0.5)).
struct SphereCircle {
  double x_px = 0, y_px = 0, radius_px = 0;
};

struct CalibrationRequest {
  std::string name;                 // DATA/calibrations/NAME
  std::vector<std::string> stacks;  // chrome-sphere stacks, one per sphere position
  bool allow_missing = false;
  nlohmann::json to_json() const;
};

struct SolveRequest {
  std::string stack;
  std::string method = "l2";
  std::string calibration;  // a calibration's name; empty = the stack's lights
  std::string name;         // DATA/results/NAME; empty = STACK-METHOD
  nlohmann::json to_json() const;
};

// Each throws Refused(400) naming the field at fault.
LedsRequest leds_request(const nlohmann::json& body);
PreviewRequest preview_request(const nlohmann::json& body);
TestSequenceRequest test_sequence_request(const nlohmann::json& body);
CaptureRequest capture_request(const nlohmann::json& body);
CalibrationRequest calibration_request(const nlohmann::json& body);
SphereCircle sphere_request(const nlohmann::json& body);
SolveRequest solve_request(const nlohmann::json& body);

}  // namespace lightstage::station
