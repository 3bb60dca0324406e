// `lightstage export --format relight`, `export` from a solve folder and
// `relight --holdout` end to end, on small simulated stacks.
#include "lightstage/host/io/relight_web.hpp"
#include "lightstage/host/io/rti_files.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"
#include "lightstage/testing/sanitizers.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

namespace lightstage {
namespace {

using testing::run_lightstage;

std::filesystem::path simulate(const std::filesystem::path& dir, const std::string& scene = "bumps") {
  const auto run = run_lightstage({"simulate", "--scene", scene, "--lights", "distant", "--noise", "none",
                                   "--width", "32", "--height", "32", "--out", (dir / "stack").string()});
  EXPECT_EQ(run.exit_code, 0) << run.err;
  return dir / "stack";
}

std::string bytes_of(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(ExportRelight, WritesInfoAndPlanesThatReadBack) {
  const auto dir = testing::scratch_dir();
  const auto stack = simulate(dir);
  auto run = run_lightstage({"export", "--input", stack.string(), "--format", "relight", "--model", "hsh",
                             "--out", (dir / "web").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("relight hsh3 32x32, 9 terms"), std::string::npos) << run.out;
  // rgb (the default) of HSH order 3: 27 planes in 9 JPEGs.
  for (int j = 0; j < 9; ++j)
    EXPECT_TRUE(std::filesystem::is_regular_file(dir / "web" / fmt::format("plane_{}.jpg", j)));
  EXPECT_FALSE(std::filesystem::exists(dir / "web/plane_9.jpg"));
  const io::RtiImage back = io::read_relight_web(dir / "web");
  EXPECT_EQ(back.basis, RtiBasis::hsh3);
  EXPECT_EQ(back.width, 32);

  run = run_lightstage({"export", "--input", stack.string(), "--format", "relight", "--colour", "lrgb",
                        "--planes", "png", "--out", (dir / "web-lrgb").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(io::parse_relight_info(bytes_of(dir / "web-lrgb/info.json"), "info.json").nplanes,
            9);  // ptm lrgb
  EXPECT_TRUE(std::filesystem::is_regular_file(dir / "web-lrgb/plane_2.png"));

  // An existing, non-empty --out is refused.
  run = run_lightstage(
      {"export", "--input", stack.string(), "--format", "relight", "--out", (dir / "web").string()});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("--out"), std::string::npos) << run.err;
}

TEST(ExportFromSolve, FollowsTheSolveToItsStack) {
  const auto dir = testing::scratch_dir();
  const auto stack = simulate(dir);
  auto run = run_lightstage({"solve", "--input", stack.string(), "--out", (dir / "result").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  run = run_lightstage({"export", "--input", (dir / "result").string(), "--format", "ptm", "--out",
                        (dir / "from-solve.ptm").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("of " + stack.string()), std::string::npos) << run.out;
  run = run_lightstage(
      {"export", "--input", stack.string(), "--format", "ptm", "--out", (dir / "from-stack.ptm").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(bytes_of(dir / "from-solve.ptm"), bytes_of(dir / "from-stack.ptm"));

  // The solve's stack moved away: the error names summary.json and says what to do.
  std::filesystem::rename(stack, dir / "moved");
  run = run_lightstage(
      {"export", "--input", (dir / "result").string(), "--format", "hsh", "--out", (dir / "x.rti").string()});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find((dir / "result/summary.json").string() + ": input: the solve's stack"),
            std::string::npos)
      << run.err;
  EXPECT_NE(run.err.find("--input STACK"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.rti"));
}

TEST(RelightHoldout, ReportsEveryModelLikeBenchHoldout) {
  LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY("ExportFromSolve.FollowsTheSolveToItsStack");
  const auto dir = testing::scratch_dir();
  const auto stack = simulate(dir, "sphere");
  auto run = run_lightstage({"relight", "--holdout", "--input", stack.string(), "--held-out", "3",
                             "--methods", "biquadratic", "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto r = nlohmann::json::parse(run.out);
  ASSERT_EQ(r["held_out"].size(), 3u);
  EXPECT_EQ(r["order"], nlohmann::json({"ptm", "hsh2", "hsh3", "l2", "biquadratic"}));
  for (const auto& name : r["order"]) {
    const double e = r["models"][name.get<std::string>()]["relative_rmse"];
    EXPECT_GE(e, 0) << name;
    // A noiseless simulated sphere: every model relights an unseen light within half the photo's norm.
    EXPECT_LT(e, 0.5) << name;
  }
  // The same figures as `bench holdout`.
  run = run_lightstage({"bench", "holdout", "--input", stack.string(), "--held-out", "3", "--methods",
                        "biquadratic", "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(nlohmann::json::parse(run.out)["models"], r["models"]);

  run = run_lightstage(
      {"relight", "--holdout", "--input", stack.string(), "--held-out", "2", "--methods", "none"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("hsh3"), std::string::npos) << run.out;
  EXPECT_EQ(run.out.find("biquadratic"), std::string::npos) << run.out;

  run = run_lightstage({"relight", "--holdout", "--input", stack.string(), "--methods", "nosuch"});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("--method"), std::string::npos) << run.err;
  run = run_lightstage({"relight", "--holdout", "--input", stack.string(), "--out", (dir / "x").string()});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("--holdout"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace lightstage
