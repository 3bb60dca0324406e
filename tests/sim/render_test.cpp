#include "lightstage/sim/simulate.hpp"
#include "test_rig.hpp"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace lightstage::sim {
namespace {

using testing::make_rig;

SimulateOptions exact(const std::string& scene, LightModel model = LightModel::kDistant) {
  SimulateOptions o;
  o.scene = scene;
  o.light_model = model;
  o.sensor.noise = NoiseModel::kNone;
  o.threads = 2;
  return o;
}

// Shading at unit light recovered from a frame: (DN - black) / 65535 / intensity.
double shading(const Frame& f, int r, int c) {
  return (f.image.at<std::uint16_t>(r, c) - f.black_level) / 65535.0 / f.light_intensity.x();
}

Vec3 normal_at(const ImageStack& s, int r, int c) {
  const auto n = s.ground_truth->normals.at<cv::Vec3f>(r, c);
  return {n[0], n[1], n[2]};
}

TEST(SimRender, LightFromPlusXBrightensTheRightAndPlusYTheTop) {
  const Rig rig = make_rig({{300, 0, 100}, {0, 300, 100}});
  const ImageStack s = simulate_stack(rig, exact("sphere"));
  const cv::Mat& right_lit = s.frames[0].image;
  const cv::Mat& top_lit = s.frames[1].image;
  const int w = s.width(), h = s.height();
  EXPECT_GT(cv::mean(right_lit.colRange(w / 2, w))[0], 5 * cv::mean(right_lit.colRange(0, w / 2))[0] + 100);
  EXPECT_GT(cv::mean(top_lit.rowRange(0, h / 2))[0], 5 * cv::mean(top_lit.rowRange(h / 2, h))[0] + 100);
  EXPECT_EQ(s.frames[0].filename, "001.png");
  EXPECT_EQ(s.frames[1].led_id, 2);
  EXPECT_TRUE(s.frames[0].light_direction.isApprox(Vec3(3, 0, 1).normalized()));
}

TEST(SimRender, LambertianShadingIsAlbedoTimesNDotL) {
  const Rig rig = make_rig({{300, 100, 200}, {-50, -200, 250}, {0, 0, 300}});
  SimulateOptions o = exact("matte-sphere");  // albedo 0.5
  o.sensor.black_level = 200;
  const ImageStack s = simulate_stack(rig, o);
  int checked = 0;
  for (const Frame& f : s.frames) {
    for (int r = 0; r < s.height(); ++r) {
      for (int c = 0; c < s.width(); ++c) {
        if (!s.mask.at<std::uint8_t>(r, c)) {
          ASSERT_EQ(f.image.at<std::uint16_t>(r, c), 200);
          continue;
        }
        const double expected = 0.5 * std::max(0.0, normal_at(s, r, c).dot(f.light_direction));
        ASSERT_NEAR(shading(f, r, c), expected, 1e-4) << r << "," << c;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 3000);
}

TEST(SimRender, WhiteLambertianFacingTheLightIsEightyPercentOfFullScale) {
  const Rig rig = make_rig({{0, 0, 300}});
  const ImageStack s = simulate_stack(rig, exact("sphere"));
  EXPECT_NEAR(s.frames[0].image.at<std::uint16_t>(32, 32), 0.8 * 65535, 0.8 * 65535 * 0.01);
}

// Near lights: per-point direction and 1/d² falloff, normalised to 1 at the
// object centre (the sphere's centre here).
TEST(SimRender, NearLightFallsOffAsInverseSquare) {
  const Vec3 led(60, 20, 90);
  const Rig rig = make_rig({led});
  SimulateOptions o = exact("sphere", LightModel::kNear);
  o.sensor.full_scale_fraction = 0.3;  // the side facing the LED gets up to 3× the centre's irradiance
  const ImageStack s = simulate_stack(rig, o);
  const double pitch = 1.6;  // the test rig camera
  int checked = 0;
  for (int r = 0; r < s.height(); ++r) {
    for (int c = 0; c < s.width(); ++c) {
      if (!s.mask.at<std::uint8_t>(r, c)) continue;
      const Vec3 x((c + 0.5 - 32) * pitch, (32 - r - 0.5) * pitch, s.ground_truth->depth.at<float>(r, c));
      const Vec3 d = led - x;
      const double expected =
          led.squaredNorm() / d.squaredNorm() * std::max(0.0, normal_at(s, r, c).dot(d.normalized()));
      ASSERT_NEAR(shading(s.frames[0], r, c), expected, 2e-4 * std::max(1.0, expected)) << r << "," << c;
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
  // A point twice as far from the LED as another, both facing it squarely,
  // receives a quarter of the irradiance: checked through the formula above;
  // and directly on the renderer:
  const Scene scene = resolve_scene("sphere");
  const Renderer renderer(scene, make_camera(rig.camera, {}, std::nullopt, std::nullopt), Vec3::Zero(),
                          LightModel::kNear, 1);
  Vec3 dir;
  double e_near, e_far, dist;
  renderer.light_at(Vec3(0, 0, 200), Vec3(0, 0, 100), &dir, &e_near, &dist);
  renderer.light_at(Vec3(0, 0, 200), Vec3(0, 0, 0), &dir, &e_far, &dist);
  EXPECT_NEAR(e_near / e_far, 4.0, 1e-12);
}

// The chrome sphere's highlight centroid sits where n = normalize(l + v).
TEST(SimRender, MirrorHighlightCentroidIsWhereNormalBisectsLightAndView) {
  const std::vector<Vec3> leds = {{300, 200, 400}, {-250, 100, 300}, {50, -320, 150}, {0, 0, 500}};
  const Rig rig = make_rig(leds, 128, 128, 0.8);
  for (double radius : {2.5, 8.0}) {
    SimulateOptions o = exact("chrome-sphere");
    o.led_radius_mm = radius;
    const ImageStack s = simulate_stack(rig, o);
    for (std::size_t i = 0; i < leds.size(); ++i) {
      const Frame& f = s.frames[i];
      double sum = 0, su = 0, sv = 0;
      for (int r = 0; r < 128; ++r) {
        for (int c = 0; c < 128; ++c) {
          const double w = f.image.at<std::uint16_t>(r, c);
          sum += w;
          su += w * (c + 0.5);
          sv += w * (r + 0.5);
        }
      }
      ASSERT_GT(sum, 0) << "no highlight for LED " << i;
      const Vec3 n = (f.light_direction + Vec3::UnitZ()).normalized();
      const double u = 64 + 40 * n.x() / 0.8, v = 64 - 40 * n.y() / 0.8;
      EXPECT_LT(std::hypot(su / sum - u, sv / sum - v), 0.1) << "LED " << i << " radius " << radius;
    }
  }
}

const char* kOneBump = R"(name: one-bump
object:
  type: bumps
  size_mm: 100
  bumps: [{center_mm: [0, 0], height_mm: 15, sigma_mm: 8}]
material: lambert
)";

TEST(SimRender, CastShadowsFallBehindABumpUnderAGrazingLight) {
  const auto path = std::filesystem::temp_directory_path() / "lightstage-sim-one-bump.yaml";
  { std::ofstream(path) << kOneBump; }
  const Rig rig = make_rig({{300, 0, 40}, {0, 0, 300}});  // grazing from +x (7.6°), overhead
  SimulateOptions o = exact(path.string());
  const ImageStack lit = simulate_stack(rig, o);
  o.cast_shadows = false;
  const ImageStack unshadowed = simulate_stack(rig, o);
  // Behind the bump (x = -29.6 mm, y = 0: pixel column 13, row 32) the plane faces
  // the grazing light but sits in the bump's shadow.
  EXPECT_EQ(lit.frames[0].image.at<std::uint16_t>(32, 13), 0);
  EXPECT_GT(unshadowed.frames[0].image.at<std::uint16_t>(32, 13), 1000);
  // In front of the bump it is lit.
  EXPECT_GT(lit.frames[0].image.at<std::uint16_t>(32, 50), 1000);
  // Overhead: no pixel that faces the light is dark.
  for (int r = 0; r < lit.height(); ++r) {
    for (int c = 0; c < lit.width(); ++c) {
      if (normal_at(lit, r, c).dot(lit.frames[1].light_direction) > 0.05) {
        ASSERT_EQ(lit.frames[1].image.at<std::uint16_t>(r, c),
                  unshadowed.frames[1].image.at<std::uint16_t>(r, c));
      }
    }
  }
  std::filesystem::remove(path);
}

TEST(SimRender, BunnyHasSelfShadowsAndABackground) {
  const Rig rig = make_rig({{300, 0, 60}});
  SimulateOptions o = exact("bunny");
  const ImageStack s = simulate_stack(rig, o);
  int shadowed = 0, background = 0;
  for (int r = 0; r < s.height(); ++r) {
    for (int c = 0; c < s.width(); ++c) {
      if (!s.mask.at<std::uint8_t>(r, c)) {
        ++background;
      } else if (normal_at(s, r, c).dot(s.frames[0].light_direction) > 0.1 &&
                 s.frames[0].image.at<std::uint16_t>(r, c) == 0) {
        ++shadowed;
      }
    }
  }
  EXPECT_GT(background, 500);
  EXPECT_GT(shadowed, 10);
}

// Ground-truth normals agree with central differences of the ground-truth depth.
TEST(SimRender, NormalsMatchDepthDifferences) {
  const Rig rig = make_rig({{0, 0, 300}}, 128, 128, 0.8);
  for (const char* scene : {"bumps", "sphere"}) {
    const ImageStack s = simulate_stack(rig, exact(scene));
    const cv::Mat& z = s.ground_truth->depth;
    double worst = 0, total = 0;
    int count = 0;
    for (int r = 1; r < 127; ++r) {
      for (int c = 1; c < 127; ++c) {
        if (!s.mask.at<std::uint8_t>(r - 1, c) || !s.mask.at<std::uint8_t>(r + 1, c) ||
            !s.mask.at<std::uint8_t>(r, c - 1) || !s.mask.at<std::uint8_t>(r, c + 1)) {
          continue;
        }
        const Vec3 n = normal_at(s, r, c);
        if (n.z() < 0.5) continue;  // the sphere's limb: differences are poor there
        const double dzdx = (z.at<float>(r, c + 1) - z.at<float>(r, c - 1)) / (2 * 0.8);
        const double dzdy = (z.at<float>(r - 1, c) - z.at<float>(r + 1, c)) / (2 * 0.8);
        const double err = angle_between_deg(n, Vec3(-dzdx, -dzdy, 1).normalized());
        worst = std::max(worst, err);
        total += err;
        ++count;
      }
    }
    EXPECT_GT(count, 5000) << scene;
    EXPECT_LT(total / count, 0.1) << scene;
    EXPECT_LT(worst, 1.0) << scene;
  }
}

TEST(SimRender, ImagesDoNotDependOnThreadCount) {
  const Rig rig = make_rig({{200, 100, 150}, {-100, 0, 250}});
  SimulateOptions o;
  o.scene = "bunny";
  o.width = o.height = 40;
  o.seed = 99;
  o.threads = 1;
  const ImageStack a = simulate_stack(rig, o);
  o.threads = 3;
  const ImageStack b = simulate_stack(rig, o);
  for (std::size_t i = 0; i < a.frames.size(); ++i) {
    EXPECT_EQ(cv::norm(a.frames[i].image, b.frames[i].image, cv::NORM_INF), 0.0);
  }
  o.seed = 100;
  const ImageStack c = simulate_stack(rig, o);
  EXPECT_GT(cv::norm(a.frames[0].image, c.frames[0].image, cv::NORM_INF), 0.0);
}

TEST(SimRender, PinholeCameraSeesTheSphere) {
  Rig rig = make_rig({{0, 0, 300}});
  rig.camera.model = CameraModel::kPinhole;
  rig.camera.focal_px = 400;
  rig.camera.position_mm = Vec3(0, 0, 600);
  const ImageStack s = simulate_stack(rig, exact("sphere"));
  // A 40 mm sphere at 600 mm with f = 400 px: radius about 400·40/sqrt(600²-40²) ≈ 26.7 px.
  const double area = cv::countNonZero(s.mask);
  EXPECT_NEAR(std::sqrt(area / kPi), 400 * 40 / std::sqrt(600.0 * 600 - 40 * 40), 1.0);
}

}  // namespace
}  // namespace lightstage::sim
