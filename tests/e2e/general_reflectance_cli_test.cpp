// Issue 6 through the CLI: solve --method for every general-reflectance
// method on a simulated glossy sphere, relight from the result, reflectometry
// with the ground truth, the material sweep, and bad input.
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"
#include "lightstage/testing/sanitizers.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <map>
#include <string>

namespace lightstage {
namespace {

using testing::run_lightstage;

nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

class GeneralReflectanceCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing::scratch_dir();
    const auto run =
        run_lightstage({"simulate", "--scene", "sphere", "--material", "cook-torrance:roughness=0.3,ks=0.5",
                        "--lights", "distant", "--noise", "none", "--width", "48", "--height", "48", "--out",
                        (dir_ / "stack").string()});
    ASSERT_EQ(run.exit_code, 0) << run.err;
  }
  static std::filesystem::path dir_;
};
std::filesystem::path GeneralReflectanceCli::dir_;

// Flags another method refuses are fine for the one that takes them: l2 keeps
// every observation with --shadow-threshold -1.
TEST_F(GeneralReflectanceCli, L2TakesTheShadowThresholdThatKeepsEverything) {
  const auto run = run_lightstage({"solve", "--input", (dir_ / "stack").string(), "--method", "l2",
                                   "--shadow-threshold", "-1", "--out", (dir_ / "l2-all").string()});
  EXPECT_EQ(run.exit_code, 0) << run.err;
}

TEST_F(GeneralReflectanceCli, EveryMethodSolvesAndBeatsL2) {
  LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY("GeneralReflectanceCli.ReflectanceFitsEveryModel");
  auto run = run_lightstage(
      {"solve", "--input", (dir_ / "stack").string(), "--method", "l2", "--out", (dir_ / "l2").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const double l2 =
      read_json(dir_ / "l2" / "summary.json")["error_vs_ground_truth"]["mean_deg"].get<double>();
  for (const std::string method : {"robust", "monotonic", "bilinear", "biquadratic", "auto"}) {
    const auto out = dir_ / method;
    run = run_lightstage({"solve", "--input", (dir_ / "stack").string(), "--method", method, "--threads", "2",
                          "--out", out.string()});
    ASSERT_EQ(run.exit_code, 0) << method << ": " << run.err;
    const auto summary = read_json(out / "summary.json");
    EXPECT_EQ(summary["method"], method);
    EXPECT_TRUE(std::filesystem::exists(out / "confidence.pfm")) << method;
    const double error = summary["error_vs_ground_truth"]["mean_deg"].get<double>();
    EXPECT_LT(error, l2) << method;
    // Monotonic (azimuth from robust by default) carries its elevation search error: a few degrees looser.
    EXPECT_LT(error, method == "monotonic" ? 6.0 : 3.0) << method;
  }
  const auto summary = read_json(dir_ / "biquadratic" / "summary.json");
  EXPECT_EQ(summary["reflectance"]["order"], 2);
  // The start's fall-off is estimated from the object and recorded; a sphere of
  // Lambert + Cook–Torrance has none.
  const auto& falloff = summary["parameters"]["falloff"];
  EXPECT_TRUE(falloff["estimated"].get<bool>());
  EXPECT_LT(std::abs(falloff["kappa"].get<double>()), 0.05);
  EXPECT_GT(falloff["pixels"].get<int>(), 1000);
  EXPECT_TRUE(read_json(dir_ / "auto" / "summary.json")["parameters"]["bipolynomial"]["falloff"]["estimated"]
                  .get<bool>());
  // Nine coefficients, and the relighting fit's specular lobe weight when it chose one.
  const bool lobe = summary["reflectance"].contains("specular");
  ASSERT_EQ(summary["files"]["brdf"].size(), lobe ? 10u : 9u);
  EXPECT_TRUE(std::filesystem::exists(dir_ / "biquadratic" / "brdf_C00.pfm"));
  EXPECT_EQ(std::filesystem::exists(dir_ / "biquadratic" / "brdf_S.pfm"), lobe);
}

TEST_F(GeneralReflectanceCli, AGivenFalloffIsUsedAsIs) {
  std::map<std::string, nlohmann::json> summaries;
  for (const char* kappa : {"+0.3", "0"}) {
    const auto out = dir_ / (std::string("biquadratic-falloff-") + kappa);
    const auto run = run_lightstage({"solve", "--input", (dir_ / "stack").string(), "--method", "biquadratic",
                                     "--falloff", kappa, "--out", out.string()});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    summaries[kappa] = read_json(out / "summary.json");
    EXPECT_FALSE(summaries[kappa]["parameters"]["falloff"]["estimated"].get<bool>());
  }
  EXPECT_EQ(summaries["+0.3"]["parameters"]["falloff"]["kappa"].get<double>(), 0.3);
  EXPECT_EQ(summaries["0"]["parameters"]["falloff"]["kappa"].get<double>(), 0.0);
  // The value reaches the start: a wrong κ on this Lambert + Cook–Torrance sphere costs accuracy.
  EXPECT_GT(summaries["+0.3"]["error_vs_ground_truth"]["mean_deg"].get<double>(),
            summaries["0"]["error_vs_ground_truth"]["mean_deg"].get<double>() + 0.05);
}

TEST_F(GeneralReflectanceCli, MonotonicTakesItsAzimuthFromAnotherMethod) {
  const auto out = dir_ / "monotonic-from-l2";
  const auto run = run_lightstage({"solve", "--input", (dir_ / "stack").string(), "--method", "monotonic",
                                   "--azimuth-from", "biquadratic", "--out", out.string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(read_json(out / "summary.json")["parameters"]["azimuth"], "biquadratic");
}

TEST_F(GeneralReflectanceCli, RelightWritesOneFramePerLight) {
  const auto result = dir_ / "relight-source";
  auto run = run_lightstage(
      {"solve", "--input", (dir_ / "stack").string(), "--method", "biquadratic", "--out", result.string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  run = run_lightstage({"relight", "--input", result.string(), "--light", "0.5,0.2,0.8", "--turntable", "3",
                        "--out", (dir_ / "relit").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto summary = read_json(dir_ / "relit" / "relight.json");
  EXPECT_EQ(summary["model"], "bipolynomial");
  ASSERT_EQ(summary["frames"].size(), 4u);
  EXPECT_TRUE(std::filesystem::exists(dir_ / "relit" / "relit_003.png"));
}

TEST_F(GeneralReflectanceCli, ReflectanceFitsEveryModel) {
  const auto run = run_lightstage({"reflectance", "--input", (dir_ / "stack").string(), "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto result = nlohmann::json::parse(run.out);
  ASSERT_EQ(result["fits"].size(), 5u);
  double lambert = 0, biquadratic = 0;
  for (const auto& fit : result["fits"]) {
    if (fit["model"] == "lambert") lambert = fit["rmse"].get<double>();
    if (fit["model"] == "biquadratic") biquadratic = fit["rmse"].get<double>();
  }
  EXPECT_LT(biquadratic, lambert);
}

TEST(GeneralReflectanceCliSweep, BenchMaterialsPrintsTheTableAndPlot) {
  const auto out = testing::scratch_dir();
  const auto run =
      run_lightstage({"bench", "materials", "--materials", "lambert;ward:alpha=0.2,ks=0.5", "--methods",
                      "l2,biquadratic", "--noise", "none,0.05", "--lights", "40", "--out", out.string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("biquadratic"), std::string::npos);
  EXPECT_NE(run.out.find("lambda=0.05"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(out / "materials.png"));
  const auto result = read_json(out / "materials.json");
  EXPECT_LT(result["mean_errors_deg"][0][0]["biquadratic"].get<double>(),
            result["mean_errors_deg"][0][0]["l2"].get<double>());
}

// Issue 6's targets on the whole default sweep (21 materials, 100 lights):
// biquadratic ≤ 1.5° without noise, and monotonic, biquadratic and auto each
// more accurate than l2 and robust on average. Measured (none / λ = 0.05 /
// 0.15): robust 1.32 / 1.30 / 1.39, monotonic 1.06 / 1.22 / 1.55,
// biquadratic 0.59 / 0.86 / 1.52, auto 0.50 / 0.79 / 1.39. Each beats l2 at
// every level and robust at the first two; at λ = 0.15 robust's shot-noise
// refit (docs/solvers.md) draws level with auto and pulls ahead of the other two,
// so against robust the test holds the issue's measure, the mean over the levels.
TEST(GeneralReflectanceCliSweep, IssueTargetsHoldOnTheDefaultSweep) {
  LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY("GeneralReflectanceCliSweep.BenchMaterialsPrintsTheTableAndPlot");
  const auto out = testing::scratch_dir();
  const auto run = run_lightstage({"bench", "materials", "--methods", "l2,robust,monotonic,biquadratic,auto",
                                   "--noise", "none,0.05,0.15", "--out", out.string(), "--quiet"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto result = read_json(out / "materials.json");
  ASSERT_EQ(result["materials"].size(), 21u);
  const auto& rows = result["mean_errors_deg"][0];
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_LE(rows[0]["biquadratic"].get<double>(), 1.5);
  const auto mean = [&](const char* method) {
    double sum = 0;
    for (const auto& row : rows) sum += row[method].get<double>();
    return sum / static_cast<double>(rows.size());
  };
  for (const char* method : {"monotonic", "biquadratic", "auto"}) {
    for (std::size_t row = 0; row < rows.size(); ++row) {
      EXPECT_LT(rows[row][method].get<double>(), rows[row]["l2"].get<double>())
          << method << " vs l2 at noise " << result["noise"][row];
      if (row < 2) {
        EXPECT_LT(rows[row][method].get<double>(), rows[row]["robust"].get<double>())
            << method << " vs robust at noise " << result["noise"][row];
      }
    }
    EXPECT_LT(mean(method), mean("robust")) << method << " vs robust on average";
  }
}

TEST(GeneralReflectanceCliErrors, BadInputNamesTheFlag) {
  auto run = run_lightstage({"solve", "--input", "x", "--out", "y", "--method", "nope"});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE((run.out + run.err).find("--method"), std::string::npos);
  run = run_lightstage({"relight", "--input", "/nonexistent", "--light", "1,2", "--out", "y"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("--light"), std::string::npos) << run.err;
  run = run_lightstage({"bench", "materials", "--noise", "loud"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("--noise"), std::string::npos) << run.err;
  run = run_lightstage({"bench", "materials", "--light-cone", "5"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("--light-cone"), std::string::npos) << run.err;
  // --falloff: out of range or not a number, for solve and bench, before any input is read or simulated.
  for (const char* value : {"7", "-0.51", "steep", "", "inf", "0.3x"}) {
    run = run_lightstage(
        {"solve", "--input", "x", "--out", "y", "--method", "biquadratic", "--falloff", value});
    EXPECT_EQ(run.exit_code, 1) << value;
    EXPECT_NE(run.err.find("--falloff"), std::string::npos) << run.err;
    run = run_lightstage({"bench", "materials", "--falloff", value});
    EXPECT_EQ(run.exit_code, 1) << value;
    EXPECT_NE(run.err.find("--falloff"), std::string::npos) << run.err;
  }
  run = run_lightstage(
      {"solve", "--input", "x", "--out", "y", "--method", "auto", "--plateau-tolerance", "-1"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("--plateau-tolerance"), std::string::npos) << run.err;
  run = run_lightstage({"bench", "materials", "--materials", "unobtainium"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("unobtainium"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace lightstage
