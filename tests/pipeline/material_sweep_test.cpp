#include "lightstage/pipeline/material_sweep.hpp"

#include "lightstage/common/error.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace lightstage::pipeline {
namespace {

TEST(MaterialSweep, SolvesEveryCellAndRanksTheMethodsAsTheDissertation) {
  MaterialSweepOptions options;
  options.materials = {"lambert", "cook-torrance:roughness=0.3,ks=0.5"};
  options.methods = {"l2", "lambert-low", "biquadratic"};
  options.noise = {-1};
  options.light_counts = {40};
  std::size_t cells = 0;
  const MaterialSweepResult result = run_material_sweep(options, [&cells](std::size_t n) { cells += n; });
  EXPECT_EQ(cells, options.cells());
  EXPECT_EQ(cells, 6u);
  ASSERT_EQ(result.errors.size(), 1u);
  const auto& errors = result.errors[0][0];  // [material][method]
  // l2 keeps the attached shadows, as published, so it is far off even on Lambert;
  // Lambert without the shadows and the bi-polynomial are exact there.
  EXPECT_GT(errors[0][0], 2.0);
  EXPECT_LT(errors[0][1], 0.5);
  EXPECT_LT(errors[0][2], 0.5);
  // Cook–Torrance: the bi-polynomial and Lambert on the darkest quarter (below
  // the specular lobe) stay accurate where l2 is far off.
  EXPECT_LT(errors[1][1], 0.5);
  EXPECT_LT(errors[1][2], 0.5);
  EXPECT_GT(errors[1][0], 2.0);
  for (const double pps : result.pixels_per_second) EXPECT_GT(pps, 0);
  const nlohmann::json json = result.to_json();
  EXPECT_TRUE(json.is_object());
  EXPECT_FALSE(result.summary_table(0).empty());
}

TEST(MaterialSweep, BadOptionsNameTheirFlag) {
  MaterialSweepOptions options;
  options.methods = {"lambertian"};
  EXPECT_THROW(options.check(), InputError);
  options = {};
  options.light_counts = {10};
  EXPECT_THROW(options.check(), InputError);
  options = {};
  options.falloff = "steep";
  EXPECT_THROW(options.check(), InputError);
  options = {};
  options.light_cone_deg = 10;
  EXPECT_THROW(options.check(), InputError);
}

}  // namespace
}  // namespace lightstage::pipeline
