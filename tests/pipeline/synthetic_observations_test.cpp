#include "lightstage/pipeline/synthetic_observations.hpp"

#include "lightstage/common/error.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace lightstage::pipeline {
namespace {

TEST(RandomHemisphereLights, AreUnitAboveTheFloorAndRepeatable) {
  const Eigen::MatrixX3d lights = random_hemisphere_lights(200, 0.5, 9);
  ASSERT_EQ(lights.rows(), 200);
  for (Eigen::Index j = 0; j < lights.rows(); ++j) {
    EXPECT_NEAR(lights.row(j).norm(), 1.0, 1e-12);
    EXPECT_GE(lights(j, 2), 0.5);
  }
  EXPECT_EQ(lights, random_hemisphere_lights(200, 0.5, 9));
  EXPECT_NE(lights, random_hemisphere_lights(200, 0.5, 10));
  EXPECT_THROW(random_hemisphere_lights(0, 0.5, 1), InputError);
  EXPECT_THROW(random_hemisphere_lights(10, 1.0, 1), InputError);
}

TEST(SweepGrid, HoldsTheDissertationsNormals) {
  EXPECT_EQ(sweep_grid_size(), cv::Size(36, 45));
  // Row 0 is 2° elevation, the last row the view axis; column x is azimuth 10(x + 1)°.
  EXPECT_NEAR(sweep_grid_normal(0, 0).z(), std::sin(rad_from_deg(2.0)), 1e-12);
  EXPECT_NEAR(sweep_grid_normal(5, 44).z(), 1.0, 1e-12);
  const Vec3 n = sweep_grid_normal(8, 20);  // azimuth 90°
  EXPECT_NEAR(n.x(), 0.0, 1e-12);
  EXPECT_GT(n.y(), 0.0);
}

TEST(RenderSynthetic, ExactValuesAreTheBrdfTimesTheScale) {
  const sim::Material lambert = sim::parse_material("lambert");
  const Eigen::MatrixX3d lights = random_hemisphere_lights(30, 0.1, 2);
  SyntheticOptions options;
  options.scale = 0.5;
  const auto normal_at = [](int x, int y) {
    return direction_from_elevation_azimuth(rad_from_deg(30 + 10.0 * y), rad_from_deg(40.0 * x));
  };
  const SyntheticScene scene = render_synthetic(lambert, cv::Size(4, 3), normal_at, lights, options);
  const Observations& obs = scene.observations;
  ASSERT_EQ(obs.pixel_count(), 12u);
  ASSERT_EQ(obs.intensities.cols(), 30);
  for (int p = 0; p < 12; ++p) {
    const auto [x, y] = std::pair{obs.pixels[p].x, obs.pixels[p].y};
    const Vec3 n = normal_at(x, y);
    const cv::Vec3f truth = scene.truth.at<cv::Vec3f>(y, x);
    EXPECT_NEAR(truth[2], n.z(), 1e-6);
    for (int j = 0; j < 30; ++j) {
      const double expected = 0.5 * lambert.shading(0, 0, n, lights.row(j).transpose(), Vec3::UnitZ());
      EXPECT_NEAR(obs.intensities(p, j), expected, 1e-6);
      EXPECT_FALSE(obs.saturated(p, j));
    }
  }
}

TEST(RenderSynthetic, NormalisesToThePeakAndQuantisesNoisyValues) {
  const sim::Material material = sim::parse_material("blinn-phong:shininess=50,ks=0.5");
  const Eigen::MatrixX3d lights = random_hemisphere_lights(50, 0.05, 3);
  SyntheticOptions exact;
  const SyntheticScene clean =
      render_synthetic(material, sweep_grid_size(), sweep_grid_normal, lights, exact);
  EXPECT_NEAR(clean.observations.intensities.maxCoeff(), 1.0f, 1e-6);

  SyntheticOptions noisy;
  noisy.noise = 0.15;
  noisy.seed = 4;
  const SyntheticScene scene =
      render_synthetic(material, sweep_grid_size(), sweep_grid_normal, lights, noisy);
  const auto& values = scene.observations.intensities;
  int saturated = 0, changed = 0;
  for (Eigen::Index p = 0; p < values.rows(); ++p) {
    for (Eigen::Index j = 0; j < values.cols(); ++j) {
      const double dn = values(p, j) * 65535.0;
      EXPECT_NEAR(dn, std::round(dn), 2e-3);  // 16-bit levels (float precision)
      EXPECT_LE(values(p, j), 1.0f);
      saturated += scene.observations.saturated(p, j) ? 1 : 0;
      changed += std::abs(values(p, j) - clean.observations.intensities(p, j)) > 1e-4 ? 1 : 0;
    }
  }
  EXPECT_GT(saturated, 0);  // the noise lifts the brightest values past full scale
  EXPECT_GT(changed, values.size() / 2);
  // The same seed gives the same noise.
  EXPECT_EQ(values, render_synthetic(material, sweep_grid_size(), sweep_grid_normal, lights, noisy)
                        .observations.intensities);
}

}  // namespace
}  // namespace lightstage::pipeline
