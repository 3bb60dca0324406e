#pragma once
// A light calibration: what `lightstage calibrate lights` measures and
// `lightstage solve --calibration` applies — per light its direction (from
// the object centre), LED position and relative intensity, with how each was
// measured and how well — and its file, calibration.json (format
// "lightstage-light-calibration", docs/calibration.md). The reader checks
// every field it uses and names file, field and value when one is wrong.

#include "lightstage/host/calibration/camera_geometry.hpp"
#include "lightstage/host/calibration/highlight.hpp"
#include "lightstage/host/calibration/led_positions.hpp"
#include "lightstage/host/calibration/mirror_sphere.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::calibration {

inline constexpr const char* kCalibrationFormat = "lightstage-light-calibration";
inline constexpr int kCalibrationVersion = 1;

// One light seen on one sphere.
struct SphereObservation {
  std::size_t sphere = 0;  // index into LightCalibration::spheres
  Highlight highlight;
  std::optional<Reflection> reflection;  // when the highlight was usable
};

struct CalibratedLight {
  std::string image;                // the light's image in the (first) chrome-sphere stack, e.g. "001.png"
  int led_id = -1;                  // from the stack's manifest; -1 when unknown
  bool measured = false;            // a direction was measured (else: every highlight missing)
  Vec3 direction = Vec3::UnitZ();   // unit, from the object centre toward the light
  std::optional<Vec3> position_mm;  // the LED, dome frame
  double position_residual_mm = 0;  // triangulation: RMS distance from the rays
  // Triangulation: the position's standard deviation along its worst-determined
  // direction, from the highlights' noise (unset for other methods).
  std::optional<double> position_sigma_mm;
  std::optional<double> reprojection_rms_px;  // triangulation: RMS highlight misfit of the fitted position
  double intensity = 1.0;                     // relative; mean 1 over the measured lights
  std::optional<double> intensity_residual;   // relative RMS misfit of the intensity fit
  std::optional<Vec3> nominal_position_mm;    // the rig's
  std::vector<SphereObservation> observations;
};

struct SphereRecord {
  std::filesystem::path stack;  // the stack folder the sphere was seen in
  MirrorSphere sphere;
};

struct LightCalibration {
  CameraGeometry camera;
  Vec3 object_position_mm = Vec3::Zero();  // where directions start and intensities hold
  std::string rig;                         // rig file used, if any
  std::optional<double> dome_radius_mm;
  // How directions were obtained: "mirror" (distant: the sphere's mirror
  // direction), "dome-radius" (one sphere, rays cut with the dome) or
  // "triangulated" (two or more sphere positions).
  std::string direction_method = "mirror";
  std::vector<SphereRecord> spheres;
  std::vector<CalibratedLight> lights;
  std::optional<NominalFit> nominal_fit;
  nlohmann::json intensity_source;    // null, or how intensities were measured
  std::vector<std::string> problems;  // every image that could not be used, and why
  std::string created;                // UTC timestamp
  std::string software;

  bool has_positions() const;
};

nlohmann::json to_json(const LightCalibration& calibration);
// Reads what to_json writes; `source` names the file in messages.
LightCalibration calibration_from_json(const nlohmann::json& j, const std::string& source);

// calibration.json on disk (written atomically).
void write_calibration(const std::filesystem::path& path, const LightCalibration& calibration);
LightCalibration read_calibration(const std::filesystem::path& path);

// light_directions.txt / light_intensities.txt lines for the measured lights, in order.
std::string directions_text(const LightCalibration& calibration);
std::string intensities_text(const LightCalibration& calibration);

}  // namespace lightstage::calibration
