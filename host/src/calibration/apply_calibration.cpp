#include "lightstage/host/calibration/apply_calibration.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/calibration/calibration_images.hpp"
#include "lightstage/host/calibration/lp_file.hpp"

#include <fmt/format.h>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <fstream>
#include <map>
#include <string>
#include <system_error>

namespace lightstage::calibration {
namespace {

namespace fs = std::filesystem;

LightCalibration from_lp(const fs::path& file) {
  LightCalibration cal;
  cal.direction_method = "lp-file";
  for (const auto& entry : read_lp(file)) {
    CalibratedLight light;
    // RTI tools write paths; the file name is what a stack lists.
    std::string name = entry.filename;
    if (const auto slash = name.find_last_of("/\\"); slash != std::string::npos)
      name = name.substr(slash + 1);
    light.image = name;
    light.measured = true;
    light.direction = entry.direction;
    cal.lights.push_back(std::move(light));
  }
  return cal;
}

std::vector<std::size_t> match(const LightCalibration& cal, const ImageStack& stack, const fs::path& file,
                               std::string* matched_by) {
  const std::size_t frames = stack.frames.size();
  std::vector<std::size_t> result(frames);
  const bool ids =
      std::all_of(stack.frames.begin(), stack.frames.end(), [](const Frame& f) { return f.led_id >= 0; }) &&
      std::all_of(cal.lights.begin(), cal.lights.end(),
                  [](const CalibratedLight& l) { return l.led_id >= 0; });
  if (ids) {
    std::map<int, std::size_t> by_id;
    for (std::size_t i = 0; i < cal.lights.size(); ++i) by_id[cal.lights[i].led_id] = i;
    for (std::size_t f = 0; f < frames; ++f) {
      const auto it = by_id.find(stack.frames[f].led_id);
      if (it == by_id.end())
        fail("{}: no light for LED {} (frame {}, {})", file.string(), stack.frames[f].led_id, f,
             stack.frames[f].filename);
      result[f] = it->second;
    }
    *matched_by = "led_id";
    return result;
  }
  std::map<std::string, std::size_t> by_name;
  for (std::size_t i = 0; i < cal.lights.size(); ++i) by_name[cal.lights[i].image] = i;
  if (cal.direction_method == "lp-file" &&
      std::all_of(stack.frames.begin(), stack.frames.end(),
                  [&](const Frame& f) { return by_name.count(f.filename) > 0; })) {
    for (std::size_t f = 0; f < frames; ++f) result[f] = by_name[stack.frames[f].filename];
    *matched_by = "filename";
    return result;
  }
  if (cal.lights.size() != frames)
    fail("{}: {} lights, but the stack has {} frames (and they carry no LED ids to match by)", file.string(),
         cal.lights.size(), frames);
  for (std::size_t f = 0; f < frames; ++f) result[f] = f;
  *matched_by = "order";
  return result;
}

// A frame's exposure × gain, 1 when the stack does not record it.
double exposure_factor(const Frame& frame) {
  return (frame.exposure_us > 0 ? frame.exposure_us : 1.0) * (frame.gain > 0 ? frame.gain : 1.0);
}

// What a frame's light intensity becomes when the calibration measured the
// lights' relative intensities: the calibrated value replaces the stack's
// relative part (which already holds whatever brightness the stack believed
// each LED has: multiplying would count it twice), while the stack's overall
// scale and each frame's exposure × gain stay, so albedo keeps its units and
// frames of different exposures stay comparable.
std::vector<Vec3> replaced_intensities(const ImageStack& stack, const LightCalibration& cal,
                                       const std::vector<std::size_t>& light_of_frame) {
  Vec3 scale = Vec3::Zero();
  double exposure = 0;
  for (const Frame& frame : stack.frames) {
    scale += frame.light_intensity;
    exposure += exposure_factor(frame);
  }
  const auto frames = static_cast<double>(stack.frames.size());
  scale /= frames;
  exposure /= frames;
  std::vector<Vec3> result;
  for (std::size_t f = 0; f < stack.frames.size(); ++f)
    result.push_back(scale *
                     (cal.lights[light_of_frame[f]].intensity * exposure_factor(stack.frames[f]) / exposure));
  return result;
}

}  // namespace

nlohmann::json StackCalibration::describe() const {
  nlohmann::json j{{"file", file.string()},
                   {"matched_by", matched_by},
                   {"direction_method", calibration.direction_method},
                   {"lights", calibration.lights.size()},
                   {"led_positions", calibration.has_positions()},
                   {"intensities_replaced", intensities_replaced}};
  return j;
}

StackCalibration apply_calibration_file(const fs::path& file, const fs::path& stack_dir, ImageStack& stack) {
  StackCalibration result;
  result.file = file;
  const bool lp = file.extension() == ".lp" || file.extension() == ".LP";
  result.calibration = lp ? from_lp(file) : read_calibration(file);
  result.light_of_frame = match(result.calibration, stack, file, &result.matched_by);
  result.intensities_replaced = !result.calibration.intensity_source.is_null();
  const std::vector<Vec3> intensities =
      result.intensities_replaced ? replaced_intensities(stack, result.calibration, result.light_of_frame)
                                  : std::vector<Vec3>{};
  for (std::size_t f = 0; f < stack.frames.size(); ++f) {
    const CalibratedLight& light = result.calibration.lights[result.light_of_frame[f]];
    if (!light.measured)
      fail("{}: light {} ({}) was not measured, but frame {} ({}) needs it", file.string(),
           result.light_of_frame[f], light.image, f, stack.frames[f].filename);
    stack.frames[f].light_direction = light.direction;
    if (result.intensities_replaced) stack.frames[f].light_intensity = intensities[f];
    if (light.position_mm) stack.frames[f].led_position_mm = light.position_mm;
  }
  std::error_code error;
  if (fs::exists(stack_dir / "manifest.json", error))
    result.stack_camera = camera_from_manifest(stack_dir / "manifest.json");
  return result;
}

bool set_near_lights(const StackCalibration& calibration, Observations& observations,
                     std::optional<double> plane_z_mm) {
  const LightCalibration& cal = calibration.calibration;
  if (!cal.has_positions()) return false;
  CameraGeometry camera = calibration.stack_camera.value_or(cal.camera);
  if (!calibration.stack_camera && (cal.camera.width != observations.image_size().width ||
                                    cal.camera.height != observations.image_size().height)) {
    fail(
        "{}: the calibration's camera is {}x{}, the stack's images are {}x{}, and the stack records no "
        "camera: "
        "cannot place its pixels for near lights (solve with --distant-lights)",
        calibration.file.string(), cal.camera.width, cal.camera.height, observations.image_size().width,
        observations.image_size().height);
  }
  if (!camera.metric)
    fail(
        "{}: the calibration's camera has no known scale; near lights need one (solve with --distant-lights)",
        calibration.file.string());
  NearLights near;
  const auto frames = static_cast<Eigen::Index>(calibration.light_of_frame.size());
  near.led_positions_mm.resize(frames, 3);
  for (Eigen::Index f = 0; f < frames; ++f) {
    near.led_positions_mm.row(f) =
        cal.lights[calibration.light_of_frame[static_cast<std::size_t>(f)]].position_mm->transpose();
  }
  near.object_centre_mm = cal.object_position_mm;
  near.points_mm = points_on_plane(
      observations.pixels,
      [&camera](const Eigen::Vector2d& uv, Eigen::Vector3d* origin, Eigen::Vector3d* direction) {
        camera.ray(uv, origin, direction);
      },
      plane_z_mm.value_or(cal.object_position_mm.z()), observations.origin);
  observations.near = std::move(near);
  return true;
}

}  // namespace lightstage::calibration

namespace lightstage::calibration {
namespace {

// `simulate --lights distant` keeps the LEDs' positions in the manifest, but its light is distant.
bool distant_simulation(const fs::path& manifest) {
  std::ifstream in(manifest);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) return false;
  const auto sim = j.find("simulation");
  if (sim == j.end() || !sim->is_object()) return false;
  const auto model = sim->find("light_model");
  return model != sim->end() && model->is_string() && model->get<std::string>() == "distant";
}

}  // namespace

bool set_stack_near_lights(const fs::path& stack_dir, const ImageStack& stack, Observations& observations,
                           std::string* why_not) {
  const auto refuse = [why_not](std::string reason) {
    if (why_not) *why_not = std::move(reason);
    return false;
  };
  if (stack.frames.empty()) return refuse("the stack has no frames");
  for (const Frame& frame : stack.frames)
    if (!frame.led_position_mm) return refuse(fmt::format("{} has no led_position_mm", frame.filename));
  std::error_code error;
  const fs::path manifest = stack_dir / "manifest.json";
  const std::optional<CameraGeometry> camera =
      fs::exists(manifest, error) ? camera_from_manifest(manifest) : std::nullopt;
  if (!camera) return refuse("the manifest records no camera to place the pixels");
  if (distant_simulation(manifest)) return refuse("the simulator rendered distant lights");
  if (!camera->metric) return refuse("the manifest's camera has no known scale");
  // The point nearest every line LED − t·direction: sum (I − d dᵀ)(c − p) = 0.
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const Frame& frame : stack.frames) {
    const Eigen::Vector3d d = frame.light_direction.normalized();
    const Eigen::Matrix3d projector = Eigen::Matrix3d::Identity() - d * d.transpose();
    a += projector;
    b += projector * *frame.led_position_mm;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(a);
  const Eigen::Vector3d spread = eigen.eigenvalues();  // ascending
  if (!(spread(0) > 1e-6 * spread(2)))
    return refuse("the frames' light directions do not meet at an object centre");
  NearLights near;
  near.object_centre_mm = a.ldlt().solve(b);
  near.led_positions_mm.resize(static_cast<Eigen::Index>(stack.frames.size()), 3);
  for (std::size_t f = 0; f < stack.frames.size(); ++f)
    near.led_positions_mm.row(static_cast<Eigen::Index>(f)) = stack.frames[f].led_position_mm->transpose();
  near.points_mm = points_on_plane(
      observations.pixels,
      [&camera](const Eigen::Vector2d& uv, Eigen::Vector3d* origin, Eigen::Vector3d* direction) {
        camera->ray(uv, origin, direction);
      },
      near.object_centre_mm.z(), observations.origin);
  observations.near = std::move(near);
  return true;
}

}  // namespace lightstage::calibration
