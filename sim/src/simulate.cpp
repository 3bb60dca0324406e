#include "lightstage/sim/simulate.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/parallel.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>

namespace lightstage::sim {
namespace {

Scene build_scene(const SimulateOptions& options) {
  Scene scene = resolve_scene(options.scene);
  if (!options.material.empty()) {
    const auto colour = scene.material.colour;  // --material replaces the lobes only
    scene.material = parse_material(options.material, scene.material.albedo);
    scene.material.colour = colour;
  }
  if (!options.colour.empty()) scene.material.colour = parse_colour(options.colour);
  if (options.cast_shadows) scene.cast_shadows = *options.cast_shadows;
  if (options.led_radius_mm) scene.led_radius_mm = *options.led_radius_mm;
  return scene;
}

}  // namespace

void SimulateOptions::check() const {
  if (scene.empty()) fail("simulate: scene must not be empty");
  if (width && (*width <= 0 || *width > 16384)) fail("simulate: width must be in 1..16384, got {}", *width);
  if (height && (*height <= 0 || *height > 16384))
    fail("simulate: height must be in 1..16384, got {}", *height);
  if (threads < 0) fail("simulate: threads must not be negative, got {}", threads);
  if (led_radius_mm && !(*led_radius_mm > 0))
    fail("simulate: led_radius_mm must be positive, got {}", *led_radius_mm);
  if (!material.empty()) parse_material(material);
  if (!colour.empty()) parse_colour(colour);
  sensor.check();
}

World::World(const Rig& rig, const SimulateOptions& options)
    : rig_(rig),
      options_((options.check(), options)),
      scene_(build_scene(options)),
      sensor_(options.sensor, rig.camera),
      renderer_(scene_, make_camera(rig.camera, scene_.camera, options.width, options.height),
                rig.object_position_mm, options.light_model, options.threads) {}

std::vector<LightSource> World::light_sources(
    const std::vector<std::pair<std::size_t, double>>& leds_on) const {
  std::vector<LightSource> lights;
  for (const auto& [index, weight] : leds_on) {
    if (index >= rig_.leds.size())
      fail("simulate: LED index {} outside the rig's {} LEDs", index, rig_.leds.size());
    lights.push_back({rig_.leds[index].position_mm, weight * rig_.leds[index].relative_intensity});
  }
  return lights;
}

cv::Mat World::render(const std::vector<std::pair<std::size_t, double>>& leds_on) const {
  return renderer_.render(light_sources(leds_on));
}

Frame World::frame(std::size_t index) const {
  const auto on = light_sources({{index, 1.0}});
  const cv::Mat shading = renderer_.has_colour() ? renderer_.render_colour(on) : renderer_.render(on);
  const Led& led = rig_.leds.at(index);
  Frame f;
  f.filename = fmt::format("{:03}.png", index + 1);
  f.image = sensor_.expose(shading, options_.seed, index);
  f.light_direction = rig_.light_direction(led);
  f.light_intensity = Vec3::Constant(led.relative_intensity * sensor_.dn_per_shading() / 65535.0);
  f.led_id = led.id;
  f.led_position_mm = led.position_mm;
  f.exposure_us = sensor_.exposure_us();
  f.gain = sensor_.gain();
  f.black_level = sensor_.black_level();
  f.saturation_level = sensor_.saturation_level();
  return f;
}

nlohmann::json World::describe() const {
  nlohmann::json j = sim::describe(options_);
  j["scene"] = scene_.describe();
  j["camera"] = renderer_.camera().describe();
  j["sensor"] = sensor_.describe();
  j["rig"] = rig_.name;
  return j;
}

ImageStack simulate_stack(const Rig& rig, const SimulateOptions& options, const FrameProgress& on_frames,
                          const FrameSink& sink) {
  const auto start = std::chrono::steady_clock::now();
  const World world(rig, options);
  ImageStack stack;
  // Frames in parallel too (each renders its rows in parallel): the sensor
  // stage of one overlaps the rendering of another. Noise depends only on
  // (seed, frame index), so the result does not depend on the thread count.
  stack.frames.resize(rig.leds.size());
  parallel_for(static_cast<int>(rig.leds.size()), std::min(resolve_threads(options.threads), 2), [&](int i) {
    Frame& frame = stack.frames[static_cast<std::size_t>(i)];
    frame = world.frame(static_cast<std::size_t>(i));
    if (sink) sink(static_cast<std::size_t>(i), frame);
    if (on_frames) on_frames(1);
  });
  stack.mask = world.renderer().mask().clone();
  stack.ground_truth = GroundTruth{world.renderer().ground_truth().normals.clone(),
                                   world.renderer().ground_truth().depth.clone()};
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  logger("sim")->debug("simulated {} frames of '{}' at {}x{} in {:.2f} s", stack.frames.size(), options.scene,
                       stack.width(), stack.height(), seconds);
  return stack;
}

nlohmann::json describe(const SimulateOptions& options) {
  const auto& s = options.sensor;
  nlohmann::json sensor{{"black_level", s.black_level},
                        {"full_scale_fraction", s.full_scale_fraction},
                        {"scale_to_16bit", s.scale_to_16bit},
                        {"noise", s.noise == NoiseModel::kNone       ? "none"
                                  : s.noise == NoiseModel::kPhysical ? "physical"
                                                                     : "signal-dependent"},
                        {"full_well_e", s.full_well_e},
                        {"read_noise_e", s.read_noise_e},
                        {"lambda", s.lambda},
                        {"response", s.response.describe()}};
  if (s.exposure_us) sensor["exposure_us"] = *s.exposure_us;
  if (s.gain) sensor["gain"] = *s.gain;
  if (s.bit_depth) sensor["bit_depth"] = *s.bit_depth;
  nlohmann::json j{{"simulator", "lightstage_sim"},
                   {"scene", options.scene},
                   {"light_model", light_model_name(options.light_model)},
                   {"seed", options.seed},
                   {"sensor", sensor}};
  if (!options.material.empty()) j["material"] = options.material;
  if (!options.colour.empty()) j["colour"] = options.colour;
  if (options.width) j["width"] = *options.width;
  if (options.height) j["height"] = *options.height;
  if (options.cast_shadows) j["cast_shadows"] = *options.cast_shadows;
  if (options.led_radius_mm) j["led_radius_mm"] = *options.led_radius_mm;
  return j;
}

nlohmann::json describe(const Rig& rig, const SimulateOptions& options) {
  const Scene scene = build_scene(options);
  const Sensor sensor(options.sensor, rig.camera);
  nlohmann::json j = describe(options);
  j["scene_name"] = options.scene;
  j["scene"] = scene.describe();
  j["camera"] = make_camera(rig.camera, scene.camera, options.width, options.height).describe();
  j["sensor"] = sensor.describe();
  j["rig"] = rig.name;
  return j;
}

const char* light_model_name(LightModel model) { return model == LightModel::kNear ? "near" : "distant"; }

LightModel parse_light_model(const std::string& text) {
  if (text == "near") return LightModel::kNear;
  if (text == "distant") return LightModel::kDistant;
  fail("light model must be 'near' or 'distant', got '{}'", text);
}

}  // namespace lightstage::sim
