#include "lightstage/common/error.hpp"
#include "lightstage/sim/scene_file.hpp"
#include "lightstage/sim/simulate.hpp"
#include "test_rig.hpp"

#include <gtest/gtest.h>

#include <string>

namespace lightstage::sim {
namespace {

std::string error_of(const std::string& yaml) {
  try {
    parse_scene(yaml, "scene.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(SimScene, ParsesEveryKey) {
  const Scene s = parse_scene(R"(name: custom
object:
  type: bumps
  size_mm: 60
  footprint: {shape: disk, size_mm: 50}
  bumps:
    - {center_mm: [0, 0], height_mm: 5, sigma_mm: 6}
material: "ward:alpha=0.15,ks=0.4"
albedo: {type: checker, values: [0.2, 0.8], period_mm: 5}
camera: {model: orthographic, width: 32, height: 24, pixel_pitch_mm: 2}
led_radius_mm: 4
led_radiance: 2
cast_shadows: false
)",
                              "custom.yaml");
  EXPECT_EQ(s.name, "custom");
  EXPECT_EQ(s.material.specular->describe(), "ward:alpha=0.15");
  EXPECT_DOUBLE_EQ(s.material.ks, 0.4);
  EXPECT_EQ(s.material.albedo.kind, AlbedoTexture::Kind::kChecker);
  EXPECT_EQ(*s.camera.width, 32);
  EXPECT_DOUBLE_EQ(s.led_radius_mm, 4);
  EXPECT_FALSE(s.cast_shadows);
  EXPECT_EQ(s.shape->describe()["footprint"]["shape"], "disk");
}

TEST(SimScene, ErrorsNameFileLineAndField) {
  const auto a = error_of("object: {type: sphere, radius_mm: -3}\n");
  EXPECT_NE(a.find("scene.yaml:1"), std::string::npos) << a;
  EXPECT_NE(a.find("object.radius_mm"), std::string::npos) << a;
  const auto b = error_of("object: {type: sphere, radius_mm: 3}\nmaterial: lambert\ncolour: red\n");
  EXPECT_NE(b.find("scene.yaml:3"), std::string::npos) << b;
  EXPECT_NE(b.find("colour"), std::string::npos) << b;
  const auto c = error_of("object: {type: cube}\n");
  EXPECT_NE(c.find("object.type"), std::string::npos) << c;
  const auto d = error_of("object: {type: sphere, radius_mm: 3}\nmaterial: \"ward:alpha=0\"\n");
  EXPECT_NE(d.find("material"), std::string::npos) << d;
  EXPECT_NE(d.find("alpha"), std::string::npos) << d;
  const auto e = error_of("object: [1, 2\n");
  EXPECT_NE(e.find("scene.yaml"), std::string::npos) << e;
  EXPECT_THROW(resolve_scene("no-such-preset"), InputError);
}

TEST(SimScene, EveryPresetRenders) {
  const Rig rig = testing::make_rig({{100, 50, 300}, {0, 0, 300}});
  for (const auto& name : scene_presets()) {
    SimulateOptions o;
    o.scene = name;
    o.width = o.height = 24;
    const ImageStack stack = simulate_stack(rig, o);
    ASSERT_EQ(stack.frames.size(), 2u) << name;
    EXPECT_GT(cv::countNonZero(stack.mask), 20) << name;
    EXPECT_GT(cv::norm(stack.frames[1].image, cv::NORM_INF), 0.0) << name;
  }
  SimulateOptions o;
  o.scene = "chrome-sphere";
  const auto j = describe(rig, o);
  EXPECT_EQ(j["scene"]["material"]["specular"], "chrome");
  EXPECT_EQ(j["camera"]["width"], 64);
  EXPECT_NE(std::find(scene_presets().begin(), scene_presets().end(), "chrome-sphere"),
            scene_presets().end());
}

TEST(SimScene, CameraKeepsTheFieldOfViewWhenResized) {
  CameraDefaults rig;
  rig.width = 512;
  rig.height = 256;
  rig.pixel_pitch_mm = 0.2;
  const Camera cam = make_camera(rig, {}, 128, std::nullopt);
  EXPECT_EQ(cam.height, 64);
  EXPECT_DOUBLE_EQ(cam.pixel_pitch_mm, 0.8);
}

TEST(SimScene, OptionsCheckNamesTheField) {
  SimulateOptions o;
  o.width = -2;
  try {
    o.check();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("width"), std::string::npos);
  }
  SimulateOptions m;
  m.material = "velvet";
  EXPECT_THROW(m.check(), InputError);
}

}  // namespace
}  // namespace lightstage::sim
