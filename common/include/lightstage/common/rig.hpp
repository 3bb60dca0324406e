#pragma once
// The rig description: what a dome is made of and how it is wired. Parsed from
// a YAML file (hw/rigs/*.yaml); every key is documented in docs/rig-format.md.
// Positions are millimetres in the dome frame (see geometry.hpp), times are
// microseconds.

#include "lightstage/common/geometry.hpp"

#include <algorithm>
#include <filesystem>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace lightstage {

// The longest duration any rig field may give (one hour): far beyond any LED
// limit or exposure, and far inside the nanosecond clocks' int64 range.
inline constexpr double kMaxRigDurationUs = 3'600'000'000.0;

// A GPIO line, by offset on its chip or by the name the board gives it.
struct LineRef {
  std::string name;  // empty when referenced by offset
  int offset = -1;   // -1 when referenced by name
  bool active_low = false;

  bool by_name() const { return !name.empty(); }
  std::string describe() const;  // "line 7" or "line \"LED_7\""
};

// One LED drives straight from its own GPIO line.
struct DirectWiring {
  LineRef line;
};

// One LED is bit `bit` of a shift-register chain (74HC595-style).
struct ChainWiring {
  std::string chain;  // ShiftRegisterChain::name
  int bit = 0;        // 0 = the bit shifted out last (first register's Q0)
};

using LedWiring = std::variant<DirectWiring, ChainWiring>;

struct ShiftRegisterChain {
  std::string name;
  LineRef data;
  LineRef clock;
  LineRef latch;
  std::optional<LineRef> output_enable;  // active-low OE on 74HC595
  int length = 0;                        // number of bits (8 per register)
  double clock_period_us = 1.0;
};

struct LedLimits {
  double max_on_us = 0;  // longest continuous on-time
  double max_duty = 0;   // on-time fraction over the duty window
  double duty_window_us = 1'000'000;
};

struct Led {
  int id = 0;
  Vec3 position_mm = Vec3::Zero();  // in the dome frame
  LedWiring wiring;
  std::string colour = "white";         // "white", "red", ..., or "<N>nm"
  std::optional<double> wavelength_nm;  // for narrow-band LEDs
  double relative_intensity = 1.0;      // nominal; calibration measures the real one
  LedLimits limits;
};

// A stills camera's remote-release half-press: asserted `lead_us` before the
// shutter (at the step's start), released with it. Some cameras fire only
// with it; on others it wakes the camera.
struct FocusLine {
  LineRef line;
  double lead_us = 0;
};

struct TriggerLine {
  LineRef line;  // a machine-vision trigger input, or a stills camera's shutter (full press)
  double pulse_us = 100;
  std::optional<FocusLine> focus;
  // The longest a camera takes from the trigger edge to the start of its
  // exposure (a DSLR's shutter lag): the LEDs stay lit for it as well as the exposure.
  double shutter_lag_us = 0;
  // Cameras whose shots arrive as files: the longest from the end of an
  // exposure to the file's arrival (card write, download); 0 = a streaming camera.
  double arrival_timeout_us = 0;

  // LEDs on to trigger for a step that asks `settle_us`: longer when the half-press lead is.
  double lead_us(double settle_us) const { return focus ? std::max(settle_us, focus->lead_us) : settle_us; }
};

struct StrobeLine {
  LineRef line;  // the camera's exposure-active output, read as edge events
  double timeout_us = 1'000'000;
};

enum class CameraModel { kOrthographic, kPinhole };

struct CameraDefaults {
  CameraModel model = CameraModel::kOrthographic;
  int width = 512;
  int height = 512;
  double pixel_pitch_mm = 0.2;          // orthographic: millimetres per pixel at the object
  double focal_px = 0;                  // pinhole: focal length in pixels
  Vec3 position_mm = Vec3(0, 0, 1000);  // pinhole centre in the dome frame
  double exposure_us = 10'000;
  double gain = 1.0;
  int bit_depth = 16;
  std::string uri;  // default camera backend, e.g. "sim:" or "v4l2:/dev/video0"
};

struct Rig {
  std::string name;
  std::string description;
  std::filesystem::path source;  // file it was read from, for messages
  double dome_radius_mm = 0;
  Vec3 object_position_mm = Vec3::Zero();
  CameraDefaults camera;
  TriggerLine trigger;
  std::optional<StrobeLine> strobe;
  std::vector<ShiftRegisterChain> chains;
  std::vector<Led> leds;

  const Led& led(int id) const;  // throws InputError for an unknown id
  const ShiftRegisterChain* chain(const std::string& name) const;

  // Unit direction from the object to the LED (the distant-light approximation).
  Vec3 light_direction(const Led& led) const { return (led.position_mm - object_position_mm).normalized(); }
};

// Parses a rig file. Errors name the file, the line and the field.
Rig load_rig(const std::filesystem::path& path);
// Parses rig YAML from memory; `source` names it in messages.
Rig parse_rig(const std::string& yaml_text, const std::string& source);

// The default rig: $LIGHTSTAGE_RIG_DIR/sim-dome.yaml, else the installed or
// source-tree hw/rigs/sim-dome.yaml.
std::filesystem::path default_rig_path();
std::filesystem::path rig_directory();

}  // namespace lightstage
