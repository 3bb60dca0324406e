#pragma once
// The simulated world's front door: a rig + options → an image stack with one
// frame per LED (rig order), the object mask and the ground truth. The host's
// `demo` and the simulated camera both come through here.
//
// Radiometric convention (distant lights, identity response, no noise):
//     (image - black_level) / 65535 / light_intensity = albedo · f · max(n·l, 0)
// i.e. the shading at unit light (material.hpp), up to quantisation; with
// near lights the right side also carries the 1/d² factor, normalised to 1 at
// the object centre. light_intensity (all three channels equal) is
//     relative_intensity · full_scale_fraction · (exposure/rig exposure)
//       · (gain/rig gain) · saturation_level / 65535.
//
// A scene with a colour (its `colour` key or SimulateOptions::colour) gives
// CV_16UC3 frames (BGR in memory) where channel c carries
//     kd · albedo · tint_c · diffuse · max(n·l, 0) + ks · specular · max(n·l, 0)
// (material.hpp: the highlight stays white); the tint's BT.601 grey is 1, so
// the BT.601 grey of a frame is the grey frame of the scene without colour.
// Without a colour frames are CV_16UC1, as they always were. World::render
// (the simulated camera's source) is grey either way: the virtual camera is
// monochrome and sees that BT.601 grey.

#include "lightstage/common/image_stack.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/sim/renderer.hpp"
#include "lightstage/sim/scene_file.hpp"
#include "lightstage/sim/sensor.hpp"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::sim {

struct SimulateOptions {
  std::string scene = "sphere";  // preset name or path to a scene YAML file
  std::string material;          // material preset string; empty = the scene's own
  // Colour of the diffuse albedo (parse_colour, scene_file.hpp: "0.9,0.6,0.3",
  // "patches", "{type: patches, saturation: 0.6}", ...); empty = the scene's own
  // (none: grey frames).
  std::string colour;
  LightModel light_model = LightModel::kNear;
  std::optional<int> width, height;  // override the rig camera's (keeping its field of view)
  SensorOptions sensor;
  std::uint64_t seed = 1;               // noise seed; frame i draws from (seed, i)
  int threads = 0;                      // 0 = hardware concurrency
  std::optional<bool> cast_shadows;     // override the scene's
  std::optional<double> led_radius_mm;  // override the scene's (mirror highlights)

  void check() const;
};

// A resolved world: scene, camera, renderer and sensor for one rig. Rendering
// one frame for any set of LEDs (the simulated camera's use) or the stack.
class World {
 public:
  World(const Rig& rig, const SimulateOptions& options);

  // Shading (CV_64FC1) with the given rig LEDs on; weight = fraction of the
  // exposure each was on (multiplied by its relative_intensity).
  cv::Mat render(const std::vector<std::pair<std::size_t, double>>& leds_on) const;
  // The frame for rig LED `index` alone, exposed with noise drawn from (seed,
  // index): CV_16UC3 (BGR) when the scene has a colour, else CV_16UC1.
  Frame frame(std::size_t index) const;
  bool has_colour() const { return renderer_.has_colour(); }
  // Per-pixel tint (CV_32FC3, BGR, 0 off the object): Renderer::tint_map.
  cv::Mat tint_map() const { return renderer_.tint_map(); }

  const Scene& scene() const { return scene_; }
  const Sensor& sensor() const { return sensor_; }
  const Renderer& renderer() const { return renderer_; }
  const Rig& rig() const { return rig_; }
  nlohmann::json describe() const;

 private:
  std::vector<LightSource> light_sources(const std::vector<std::pair<std::size_t, double>>& leds_on) const;

  Rig rig_;
  SimulateOptions options_;
  Scene scene_;
  Sensor sensor_;
  Renderer renderer_;
};

// `on_frames`, when set, is called with the number of frames just rendered
// (from the rendering threads, so it must be thread-safe), e.g. for a
// progress line.
using FrameProgress = std::function<void(std::size_t frames)>;
// Given each frame as it is rendered (from the rendering threads, one call per
// frame at a time for each thread), with its index: a sink may write the frame
// out and release its image, so that a stack larger than memory is simulated
// without being held (the stack returned keeps what the sink leaves).
using FrameSink = std::function<void(std::size_t index, Frame& frame)>;
ImageStack simulate_stack(const Rig& rig, const SimulateOptions& options, const FrameProgress& on_frames = {},
                          const FrameSink& sink = {});

// scene_presets() (names for --help) comes from scene_file.hpp.

// A JSON description for the stack manifest: options as given...
nlohmann::json describe(const SimulateOptions& options);
// ...and resolved against a rig (camera, sensor, scene, material).
nlohmann::json describe(const Rig& rig, const SimulateOptions& options);

const char* light_model_name(LightModel model);
LightModel parse_light_model(const std::string& text);  // "near" | "distant"

}  // namespace lightstage::sim
