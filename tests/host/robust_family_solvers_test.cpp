// The published robust family's solvers in process (low_rank.hpp,
// sparse_regression.hpp): exact on Lambertian data with attached shadows,
// far better than l2 under sparse highlights, independent of the thread
// count, and bad options named. Their comparison with `robust` on the sim
// bunnies is tests/pipeline/robust_family_test.cpp.
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "lightstage/host/solvers/low_rank.hpp"
#include "lightstage/host/solvers/sparse_regression.hpp"
#include "lightstage/testing/errors.hpp"
#include "reflectance_scene.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

namespace lightstage {
namespace {

using testing::error_of;
using testing::hemisphere_lights;
using testing::make_reflectance_scene;
using testing::mean_error;

struct Family {
  const char* name;
  std::function<SolveResult(const Observations&, int threads)> solve;
};

std::vector<Family> family() {
  return {
      {"rpca",
       [](const Observations& o, int threads) {
         RpcaOptions options;
         options.threads = threads;
         options.block_pixels = 40;  // several blocks even on a small grid
         return solve_rpca(o, options);
       }},
      {"l1",
       [](const Observations& o, int threads) {
         L1Options options;
         options.threads = threads;
         return solve_l1(o, options);
       }},
      {"sbl",
       [](const Observations& o, int threads) {
         SblOptions options;
         options.threads = threads;
         return solve_sbl(o, options);
       }},
  };
}

TEST(RobustFamilySolvers, LambertianWithAttachedShadows) {
  const auto scene = make_reflectance_scene("lambert", hemisphere_lights(60, 5));
  for (const auto& method : family()) {
    const SolveResult result = method.solve(scene.observations, 2);
    EXPECT_EQ(result.summary.method, method.name);
    EXPECT_EQ(result.summary.pixels_solved, scene.observations.pixel_count()) << method.name;
    // rpca completes the shadowed entries by the nuclear norm, not exactly on
    // a 96-pixel grid cut into 40-pixel blocks (0.45 deg measured).
    EXPECT_LT(mean_error(result, scene), std::string(method.name) == "rpca" ? 1.0 : 0.05) << method.name;
  }
}

TEST(RobustFamilySolvers, SparseHighlightsAreOutliers) {
  const auto scene = make_reflectance_scene("blinn-phong:shininess=200,ks=0.5", hemisphere_lights(80, 9));
  const double l2 = mean_error(solve_lambertian(scene.observations), scene);
  for (const auto& method : family()) {
    const double error = mean_error(method.solve(scene.observations, 2), scene);
    EXPECT_LT(error, l2 / 3) << method.name << " (l2 " << l2 << ")";
  }
}

TEST(RobustFamilySolvers, ResultsDoNotDependOnTheThreadCount) {
  const auto scene = make_reflectance_scene("ward:alpha=0.2,ks=0.5", hemisphere_lights(40, 9), 12, 8, 0.02);
  for (const auto& method : family()) {
    EXPECT_EQ(cv::norm(method.solve(scene.observations, 1).normals,
                       method.solve(scene.observations, 3).normals, cv::NORM_INF),
              0.0)
        << method.name;
  }
}

TEST(RobustFamilySolvers, RpcaRunsOfRowsEndWithTheRowThatFillsABlock) {
  using Rows = std::vector<std::size_t>;
  EXPECT_EQ(rpca_row_runs(Rows{30, 30, 30, 30, 30, 30, 30}, 64), (std::vector<int>{3, 7}));
  // A row with a block of pixels or more is a run; a short last run joins the one before...
  EXPECT_EQ(rpca_row_runs(Rows{100, 10, 60, 20}, 64), (std::vector<int>{1, 4}));
  EXPECT_EQ(rpca_row_runs(Rows{100, 10, 60, 20, 31}, 64), (std::vector<int>{1, 3, 5}));
  // ...unless it has half a block, and rows without pixels at the end join the last run.
  EXPECT_EQ(rpca_row_runs(Rows{100, 32}, 64), (std::vector<int>{1, 2}));
  EXPECT_EQ(rpca_row_runs(Rows{100, 0, 0}, 64), (std::vector<int>{3}));
  EXPECT_EQ(rpca_row_runs(Rows{0, 0, 0}, 64), (std::vector<int>{3}));
  EXPECT_EQ(rpca_row_runs(Rows{}, 64), (std::vector<int>{0}));
  // Rows [a, b) cut at run ends are split into the whole image's runs there (what bands rely on).
  Rows rows;
  for (int y = 0; y < 200; ++y)
    rows.push_back(static_cast<std::size_t>((y * 37) % 23 + (y % 50 < 5 ? 0 : 9)));
  const std::vector<int> whole = rpca_row_runs(rows, 64);
  ASSERT_GT(whole.size(), 10u);
  for (std::size_t i = 0; i + 3 < whole.size(); i += 3) {
    const int a = i == 0 ? 0 : whole[i - 1], b = whole[i + 2];
    std::vector<int> band = rpca_row_runs(Rows(rows.begin() + a, rows.begin() + b), 64);
    for (int& end : band) end += a;
    EXPECT_EQ(band, std::vector<int>(whole.begin() + static_cast<long>(i),
                                     whole.begin() + static_cast<long>(i) + 3))
        << "rows " << a << " to " << b;
  }
}

TEST(RobustFamilySolvers, BadOptionsNameTheirField) {
  const auto scene = make_reflectance_scene("lambert", hemisphere_lights(20, 1), 4, 4);
  RpcaOptions rpca;
  rpca.block_pixels = 4;
  EXPECT_NE(error_of([&] { solve_rpca(scene.observations, rpca); }).find("RpcaOptions.block_pixels"),
            std::string::npos);
  L1Options l1;
  l1.shadow_threshold = -1;
  EXPECT_NE(error_of([&] { solve_l1(scene.observations, l1); }).find("L1Options.shadow_threshold"),
            std::string::npos);
  SblOptions sbl;
  sbl.noise = 0;
  EXPECT_NE(error_of([&] { solve_sbl(scene.observations, sbl); }).find("SblOptions.noise"),
            std::string::npos);
}

TEST(RobustFamilySolvers, TooFewLitObservationsAreRejectedNotGuessed) {
  const auto scene = make_reflectance_scene("lambert", hemisphere_lights(20, 1), 4, 4);
  L1Options l1;
  l1.shadow_threshold = 10;  // every value is a shadow
  const SolveResult result = solve_l1(scene.observations, l1);
  EXPECT_EQ(result.summary.pixels_solved, 0u);
  EXPECT_EQ(result.summary.pixels_rejected_too_few_observations, scene.observations.pixel_count());
  RpcaOptions rpca;
  rpca.shadow_threshold = 10;
  const SolveResult low_rank = solve_rpca(scene.observations, rpca);
  EXPECT_EQ(low_rank.summary.pixels_solved, 0u);
  EXPECT_EQ(low_rank.summary.pixels_rejected_too_few_observations, scene.observations.pixel_count());
}

}  // namespace
}  // namespace lightstage
