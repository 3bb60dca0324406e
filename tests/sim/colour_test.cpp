// Colour albedo: dichromatic RGB frames whose BT.601 grey is the grey scene.
#include "lightstage/common/error.hpp"
#include "lightstage/sim/scene_file.hpp"
#include "lightstage/sim/simulate.hpp"
#include "test_rig.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <cmath>
#include <set>
#include <string>

namespace lightstage::sim {
namespace {

using testing::make_rig;

const char* kPatches = "{type: patches, period_mm: 12, saturation: 0.5, seed: 3}";

SimulateOptions exact(const std::string& scene, const std::string& colour = "") {
  SimulateOptions o;
  o.scene = scene;
  o.colour = colour;
  o.light_model = LightModel::kDistant;
  o.sensor.noise = NoiseModel::kNone;
  o.threads = 2;
  return o;
}

Rig three_leds() { return make_rig({{300, 100, 200}, {-50, -200, 250}, {0, 0, 300}}); }

// Shading at unit light of channel `k` (OpenCV order: 0 = B, 1 = G, 2 = R).
double channel(const Frame& f, int r, int c, int k) {
  return (f.image.at<cv::Vec3w>(r, c)[k] - f.black_level) / 65535.0 / f.light_intensity.x();
}
double grey_value(const Frame& f, int r, int c) {
  return (f.image.at<std::uint16_t>(r, c) - f.black_level) / 65535.0 / f.light_intensity.x();
}
// BT.601 grey of a BGR triple.
double bt601(double b, double g, double r) { return kGreyRed * r + kGreyGreen * g + kGreyBlue * b; }

bool saturated(const Frame& f, int r, int c) {
  const cv::Vec3w v = f.image.at<cv::Vec3w>(r, c);
  return std::max({v[0], v[1], v[2]}) >= f.saturation_level;
}

// One shading unit of quantisation error: half a code over the light intensity.
double half_code(const Frame& f) { return 0.5 / 65535.0 / f.light_intensity.x(); }

TEST(SimColour, LambertianChannelsOverTheirGreyAreTheTint) {
  const Rig rig = three_leds();
  const World world(rig, exact("matte-sphere", kPatches));  // albedo 0.5
  ASSERT_TRUE(world.has_colour());
  const cv::Mat tint = world.tint_map();
  const cv::Mat& mask = world.renderer().mask();
  ASSERT_EQ(tint.type(), CV_32FC3);
  std::set<int> hues;  // distinct tints seen, so patches really vary
  int checked = 0;
  for (std::size_t i = 0; i < rig.leds.size(); ++i) {
    const Frame f = world.frame(i);
    ASSERT_EQ(f.image.type(), CV_16UC3);
    EXPECT_EQ(f.light_intensity.x(), f.light_intensity.y());
    EXPECT_EQ(f.light_intensity.x(), f.light_intensity.z());
    for (int r = 0; r < f.image.rows; ++r) {
      for (int c = 0; c < f.image.cols; ++c) {
        const cv::Vec3f t = tint.at<cv::Vec3f>(r, c);
        if (!mask.at<std::uint8_t>(r, c)) {
          ASSERT_EQ(t, cv::Vec3f(0, 0, 0));
          continue;
        }
        ASSERT_NEAR(bt601(t[0], t[1], t[2]), 1.0, 1e-6);
        const double b = channel(f, r, c, 0), g = channel(f, r, c, 1), red = channel(f, r, c, 2);
        const double grey = bt601(b, g, red);
        if (grey < 0.05 || saturated(f, r, c)) continue;
        // Each channel is off by at most half a code: the ratio by about that over the grey.
        const double tolerance = 4 * half_code(f) / grey * std::max({t[0], t[1], t[2]});
        ASSERT_NEAR(b / grey, t[0], tolerance) << r << "," << c;
        ASSERT_NEAR(g / grey, t[1], tolerance) << r << "," << c;
        ASSERT_NEAR(red / grey, t[2], tolerance) << r << "," << c;
        hues.insert(static_cast<int>(std::lround(100 * t[2])));
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 3000);
  EXPECT_GT(hues.size(), 4u);
}

TEST(SimColour, SpecularHighlightIsWhite) {
  const Rig rig = make_rig({{120, 60, 300}});
  SimulateOptions o = exact("matte-sphere", kPatches);
  o.material = "cook-torrance:roughness=0.2,ks=0.5";
  const World world(rig, o);
  const Frame f = world.frame(0);
  ASSERT_EQ(f.image.type(), CV_16UC3);
  cv::Mat diffuse, specular;
  world.renderer().render_parts({{rig.leds[0].position_mm, rig.leds[0].relative_intensity}}, &diffuse,
                                &specular);
  const cv::Mat tint = world.tint_map();
  const cv::Mat& mask = world.renderer().mask();
  double max_highlight = 0;
  int checked = 0;
  for (int r = 0; r < f.image.rows; ++r) {
    for (int c = 0; c < f.image.cols; ++c) {
      if (!mask.at<std::uint8_t>(r, c) || saturated(f, r, c)) continue;
      const cv::Vec3f t = tint.at<cv::Vec3f>(r, c);
      const double d = diffuse.at<double>(r, c);
      // What is left after the tinted diffuse part: the same in all three channels.
      const double rest_b = channel(f, r, c, 0) - d * t[0];
      const double rest_g = channel(f, r, c, 1) - d * t[1];
      const double rest_r = channel(f, r, c, 2) - d * t[2];
      ASSERT_NEAR(rest_b, rest_g, 2.5 * half_code(f)) << r << "," << c;
      ASSERT_NEAR(rest_r, rest_g, 2.5 * half_code(f)) << r << "," << c;
      ASSERT_NEAR(rest_g, specular.at<double>(r, c), 1.5 * half_code(f)) << r << "," << c;
      max_highlight = std::max(max_highlight, rest_g);
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
  EXPECT_GT(max_highlight, 0.2);  // a real highlight was tested
}

TEST(SimColour, ChromeStaysWhite) {
  const Rig rig = make_rig({{120, 60, 300}});
  const World world(rig, exact("chrome-probe", "{type: checker, values: [[1, 0, 0], [0, 0, 1]]}"));
  const Frame f = world.frame(0);
  ASSERT_EQ(f.image.type(), CV_16UC3);
  double brightest = 0;
  for (int r = 0; r < f.image.rows; ++r) {
    for (int c = 0; c < f.image.cols; ++c) {
      const cv::Vec3w v = f.image.at<cv::Vec3w>(r, c);
      ASSERT_EQ(v[0], v[1]) << r << "," << c;
      ASSERT_EQ(v[2], v[1]) << r << "," << c;
      brightest = std::max(brightest, static_cast<double>(v[1]));
    }
  }
  EXPECT_GT(brightest, 1000);
}

TEST(SimColour, GreyOfTheColourFrameIsTheGreyFrame) {
  const Rig rig = three_leds();
  for (const std::string material : {"lambert", "cook-torrance:roughness=0.3,ks=0.5", "dielectric"}) {
    SimulateOptions grey = exact("matte-sphere");
    grey.material = material;
    SimulateOptions colour = grey;
    colour.colour = kPatches;
    const ImageStack g = simulate_stack(rig, grey);
    const ImageStack c = simulate_stack(rig, colour);
    int checked = 0;
    for (std::size_t i = 0; i < rig.leds.size(); ++i) {
      ASSERT_EQ(g.frames[i].image.type(), CV_16UC1);
      ASSERT_EQ(c.frames[i].image.type(), CV_16UC3);
      EXPECT_EQ(g.frames[i].light_intensity, c.frames[i].light_intensity);
      for (int r = 0; r < g.height(); ++r) {
        for (int col = 0; col < g.width(); ++col) {
          if (saturated(c.frames[i], r, col)) continue;
          const Frame& f = c.frames[i];
          const double from_colour =
              bt601(channel(f, r, col, 0), channel(f, r, col, 1), channel(f, r, col, 2));
          // Half a code in each channel and in the grey frame; the weights sum to 0.9999, so
          // the grey of a white highlight is 0.9999 of it.
          const double expected = grey_value(g.frames[i], r, col);
          ASSERT_NEAR(from_colour, expected, 2.1 * half_code(f) + 1.01e-4 * expected)
              << material << " frame " << i << " at " << r << "," << col;
          ++checked;
        }
      }
    }
    EXPECT_GT(checked, 10000) << material;
  }
}

TEST(SimColour, SceneWithoutColourRendersGreyAsBefore) {
  const Rig rig = three_leds();
  SimulateOptions o = exact("shiny-sphere");
  o.sensor.noise = NoiseModel::kPhysical;
  const World world(rig, o);
  EXPECT_FALSE(world.has_colour());
  const ImageStack s = simulate_stack(rig, o);
  for (std::size_t i = 0; i < rig.leds.size(); ++i) {
    ASSERT_EQ(s.frames[i].image.type(), CV_16UC1);
    // The grey path: the shading of World::render through the sensor, noise from (seed, i).
    const cv::Mat expected = world.sensor().expose(world.render({{i, 1.0}}), o.seed, i);
    ASSERT_EQ(cv::norm(s.frames[i].image, expected, cv::NORM_INF), 0) << i;
  }
  // On the object the tint of a grey scene is 1.
  const cv::Mat tint = world.tint_map();
  const cv::Mat& mask = world.renderer().mask();
  for (int r = 0; r < tint.rows; ++r)
    for (int c = 0; c < tint.cols; ++c)
      ASSERT_EQ(tint.at<cv::Vec3f>(r, c),
                mask.at<std::uint8_t>(r, c) ? cv::Vec3f(1, 1, 1) : cv::Vec3f(0, 0, 0));
}

TEST(SimColour, CameraShadingOfAColourSceneIsItsGrey) {
  // The virtual camera is monochrome: World::render is the grey scene's.
  const Rig rig = three_leds();
  const World grey(rig, exact("shiny-sphere"));
  const World colour(rig, exact("shiny-sphere", kPatches));
  const std::vector<std::pair<std::size_t, double>> on = {{0, 1.0}, {2, 0.5}};
  EXPECT_EQ(cv::norm(grey.render(on), colour.render(on), cv::NORM_INF), 0);
}

TEST(SimColour, NoiseIsPerChannelAndDeterministic) {
  const Rig rig = three_leds();
  SimulateOptions o = exact("matte-sphere", "1,1,1");
  o.sensor.noise = NoiseModel::kPhysical;
  o.threads = 1;
  const ImageStack a = simulate_stack(rig, o);
  o.threads = 3;
  const ImageStack b = simulate_stack(rig, o);
  int differ = 0;
  for (std::size_t i = 0; i < rig.leds.size(); ++i) {
    ASSERT_EQ(cv::norm(a.frames[i].image, b.frames[i].image, cv::NORM_INF), 0) << i;
    std::vector<cv::Mat> planes;
    cv::split(a.frames[i].image, planes);
    differ += cv::countNonZero(planes[0] != planes[2]);
  }
  EXPECT_GT(differ, 1000);  // independent draws, not one noise copied to three channels
}

TEST(SimColour, SpecsParse) {
  const ColourTexture constant = parse_colour("0.9, 0.6, 0.3");
  EXPECT_EQ(constant.kind, ColourTexture::Kind::kConstant);
  const Vec3 tint = constant.eval(0, 0);
  EXPECT_NEAR(bt601_grey(tint), 1.0, 1e-12);
  EXPECT_NEAR(tint.x() / tint.z(), 3.0, 1e-12);
  EXPECT_TRUE(parse_colour("[0.9, 0.6, 0.3]").eval(5, 5).isApprox(tint));

  const ColourTexture checker = parse_colour("{type: checker, values: [[1, 0, 0], [0, 0, 1]], period_mm: 5}");
  EXPECT_TRUE(checker.eval(1, 1).isApprox(Vec3(1 / kGreyRed, 0, 0)));
  EXPECT_TRUE(checker.eval(6, 1).isApprox(Vec3(0, 0, 1 / kGreyBlue)));

  const ColourTexture patches = parse_colour("patches");
  EXPECT_EQ(patches.kind, ColourTexture::Kind::kPatches);
  EXPECT_EQ(patches.saturation, 0.5);
  const ColourTexture grey_patches = parse_colour("{type: patches, saturation: 0}");
  EXPECT_TRUE(grey_patches.eval(3, 40).isApprox(Vec3::Constant(1 / bt601_grey(Vec3::Ones()))));

  const Scene scene = parse_scene(
      "object: {type: sphere, radius_mm: 10}\nmaterial: ward\ncolour: {type: patches, seed: 4}\n", "s.yaml");
  ASSERT_TRUE(scene.material.colour.has_value());
  EXPECT_EQ(scene.material.colour->seed, 4u);
  EXPECT_EQ(scene.describe()["material"]["colour"]["type"], "patches");

  // --material keeps the scene's colour; --colour replaces it.
  const Rig rig = three_leds();
  SimulateOptions o = exact("sphere", kPatches);
  o.material = "ward";
  const nlohmann::json j = describe(rig, o);
  EXPECT_EQ(j["colour"], kPatches);
  EXPECT_EQ(j["scene"]["material"]["colour"]["type"], "patches");
  EXPECT_EQ(j["scene"]["material"]["colour"]["seed"], 3);
  EXPECT_FALSE(describe(rig, exact("sphere"))["scene"]["material"].contains("colour"));
}

// The message of the InputError `f` throws.
template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

TEST(SimColour, BadSpecsNameTheKeyAndValue) {
  using ::testing::HasSubstr;
  EXPECT_THAT(error_of([] { parse_colour("{type: patches, saturation: 2}"); }),
              ::testing::AllOf(HasSubstr("'saturation'"), HasSubstr("got 2")));
  EXPECT_THAT(error_of([] { parse_colour("{type: stripes}"); }),
              ::testing::AllOf(HasSubstr("'type'"), HasSubstr("stripes")));
  EXPECT_THAT(error_of([] { parse_colour("{type: patches, seeed: 3}"); }),
              ::testing::AllOf(HasSubstr("'seeed'"), HasSubstr("unknown key")));
  EXPECT_THAT(error_of([] { parse_colour("{type: checker, saturation: 0.5}"); }),
              ::testing::AllOf(HasSubstr("'saturation'"), HasSubstr("patches only")));
  EXPECT_THAT(error_of([] { parse_colour("0.9,-1,0.3"); }), HasSubstr("-1"));
  EXPECT_THAT(error_of([] { parse_colour("0.9,x,0.3"); }), HasSubstr("'x'"));
  EXPECT_THAT(error_of([] { parse_colour("0.9,0.6"); }), HasSubstr("0.9,0.6"));
  EXPECT_THAT(error_of([] { parse_colour("[0, 0, 0]"); }), HasSubstr("black"));
  EXPECT_THAT(error_of([] { parse_colour("purple"); }), HasSubstr("'purple'"));
  EXPECT_THAT(error_of([] { parse_colour(""); }), HasSubstr("empty"));
  EXPECT_THAT(error_of([] { parse_colour("{type: patches"); }), HasSubstr("colour '{type: patches'"));
  // In a scene file: the file, the line and the field path.
  EXPECT_THAT(error_of([] {
                parse_scene(
                    "object: {type: sphere, radius_mm: 10}\ncolour:\n  type: checker\n"
                    "  values: [[1, 0, 0], [0, 0, 0]]\n",
                    "s.yaml");
              }),
              ::testing::AllOf(HasSubstr("s.yaml:4"), HasSubstr("'colour.values[1]'"), HasSubstr("black")));
  // Through the options, as `lightstage simulate --colour` passes them.
  SimulateOptions o;
  o.colour = "{type: patches, period_mm: -4}";
  EXPECT_THAT(error_of([&] { o.check(); }), ::testing::AllOf(HasSubstr("'period_mm'"), HasSubstr("-4")));
}

}  // namespace
}  // namespace lightstage::sim
