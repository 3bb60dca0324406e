// The output contract of the long commands (simulate, solve, integrate,
// bench materials): --json prints exactly one JSON object on stdout, --quiet
// prints nothing, the human mode prints its result without progress when not
// on a terminal, and a progress line is drawn when stderr is a terminal.
// Also `simulate --lighting natural` feeding `solve --method shape-prior`.
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <pty.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace lightstage {
namespace {

using testing::run_lightstage;
using testing::RunResult;

// Parses stdout as exactly one JSON object (nlohmann rejects trailing text),
// printed on one line.
nlohmann::json one_json_object(const RunResult& run) {
  EXPECT_FALSE(run.out.empty());
  EXPECT_EQ(run.out.find('\n'), run.out.size() - 1) << "more than one line on stdout:\n" << run.out;
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(run.out);
  } catch (const nlohmann::json::parse_error& e) {
    ADD_FAILURE() << "stdout is not one JSON value: " << e.what() << "\n" << run.out;
    return nlohmann::json::object();
  }
  EXPECT_TRUE(j.is_object()) << run.out;
  return j;
}

void expect_keys(const nlohmann::json& j, const std::vector<std::string>& keys) {
  for (const auto& key : keys) EXPECT_TRUE(j.contains(key)) << "missing key '" << key << "' in " << j.dump();
}

// No progress drawing (carriage returns, line clearing, estimates) in text that went to a pipe.
void expect_no_progress(const std::string& text) {
  EXPECT_EQ(text.find('\r'), std::string::npos) << text;
  EXPECT_EQ(text.find("\033[K"), std::string::npos) << text;
  EXPECT_EQ(text.find("ETA"), std::string::npos) << text;
}

std::vector<std::string> small_stack_args(const std::filesystem::path& out) {
  return {"simulate", "--scene", "sphere",   "--lights", "distant", "--noise",   "none",
          "--width",  "40",      "--height", "40",       "--out",   out.string()};
}

std::vector<std::string> with(std::vector<std::string> args, const std::vector<std::string>& more) {
  args.insert(args.end(), more.begin(), more.end());
  return args;
}

TEST(ProgressOutput, SimulateJsonQuietAndHuman) {
  const auto dir = testing::scratch_dir();
  auto run = run_lightstage(with(small_stack_args(dir / "json"), {"--json"}));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto j = one_json_object(run);
  expect_keys(j, {"stack", "frames", "width", "height", "seconds", "total_seconds", "lighting"});
  EXPECT_EQ(j.value("frames", 0), 96);
  EXPECT_EQ(j.value("width", 0), 40);
  EXPECT_EQ(j.value("lighting", ""), "dome");
  EXPECT_TRUE(std::filesystem::exists(dir / "json/manifest.json"));
  expect_no_progress(run.err);

  run = run_lightstage(with(small_stack_args(dir / "quiet"), {"--quiet"}));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.out, "");
  EXPECT_EQ(run.err, "") << "--quiet prints nothing but errors";
  EXPECT_TRUE(std::filesystem::exists(dir / "quiet/mask.png"));

  run = run_lightstage(small_stack_args(dir / "human"));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("96 frames of 40x40"), std::string::npos) << run.out;
  expect_no_progress(run.out);
  expect_no_progress(run.err);

  // Errors still reach stderr under --quiet.
  run = run_lightstage({"simulate", "--scene", "no-such-scene", "--out", (dir / "bad").string(), "--quiet"});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_EQ(run.out, "");
  EXPECT_NE(run.err.find("no-such-scene"), std::string::npos) << run.err;
}

TEST(ProgressOutput, SolveAndIntegrateJsonAndQuiet) {
  const auto dir = testing::scratch_dir();
  auto run = run_lightstage(with(small_stack_args(dir / "stack"), {"--quiet"}));
  ASSERT_EQ(run.exit_code, 0) << run.err;

  for (const std::string method : {"l2", "robust"}) {
    run = run_lightstage({"solve", "--input", (dir / "stack").string(), "--method", method,
                          "--shadow-threshold", "0.001", "--out", (dir / ("result-" + method)).string(),
                          "--json"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const auto j = one_json_object(run);
    expect_keys(j, {"method", "pixels_solved", "pixels_in_mask", "seconds", "total_seconds", "files", "out",
                    "error_vs_ground_truth"});
    EXPECT_EQ(j.value("method", ""), method);
    EXPECT_GT(j.value("pixels_solved", 0), 0);
    EXPECT_LT(j["error_vs_ground_truth"].value("mean_deg", 99.0), 2.0) << j.dump();
    expect_no_progress(run.err);
  }

  run = run_lightstage(
      {"solve", "--input", (dir / "stack").string(), "--out", (dir / "quiet").string(), "--quiet"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.out, "");
  EXPECT_EQ(run.err, "");
  EXPECT_TRUE(std::filesystem::exists(dir / "quiet/normal.png"));

  run = run_lightstage({"solve", "--input", (dir / "stack").string(), "--out", (dir / "human").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("l2: solved"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("angular error over"), std::string::npos) << run.out;
  expect_no_progress(run.err);

  run = run_lightstage(
      {"integrate", "--input", (dir / "result-l2").string(), "--out", (dir / "surface").string(), "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto surface = one_json_object(run);
  expect_keys(surface, {"out", "total_seconds", "mesh"});
  expect_no_progress(run.err);

  run = run_lightstage({"integrate", "--input", (dir / "result-l2").string(), "--out",
                        (dir / "surface-q").string(), "--quiet"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.out, "");
  EXPECT_EQ(run.err, "");
  EXPECT_TRUE(std::filesystem::exists(dir / "surface-q/depth.pfm"));
}

TEST(ProgressOutput, BenchMaterialsJsonAndQuiet) {
  const auto dir = testing::scratch_dir();
  const std::vector<std::string> sweep = {"bench",     "materials",   "--lights", "20",        "--noise",
                                          "none,0.05", "--materials", "lambert",  "--methods", "l2,robust"};
  auto run = run_lightstage(with(sweep, {"--json", "--out", (dir / "sweep").string()}));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto j = one_json_object(run);
  expect_keys(j, {"errors_deg", "mean_errors_deg", "methods", "pixels_per_second", "seconds", "outputs"});
  EXPECT_EQ(j["outputs"].value("json", ""), (dir / "sweep/materials.json").string());
  EXPECT_TRUE(std::filesystem::exists(dir / "sweep/materials.png"));
  expect_no_progress(run.err);

  run = run_lightstage(with(sweep, {"--quiet"}));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.out, "");
  EXPECT_EQ(run.err, "");
}

// Runs bin/lightstage with stderr on a pseudo-terminal (stdout to /dev/null)
// and returns what it drew there.
std::string run_on_terminal(const std::vector<std::string>& args) {
  int master = -1, slave = -1;
  if (::openpty(&master, &slave, nullptr, nullptr, nullptr) != 0) {
    ADD_FAILURE() << "openpty: " << std::strerror(errno);
    return {};
  }
  const std::string program = (testing::bin_dir() / "lightstage").string();
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(program.c_str()));
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(master);
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, STDOUT_FILENO);
    ::dup2(slave, STDERR_FILENO);
    ::execv(program.c_str(), argv.data());
    ::_exit(127);
  }
  ::close(slave);
  std::string text;
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::read(master, buffer, sizeof buffer);
    if (n > 0) {
      text.append(buffer, static_cast<std::size_t>(n));
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else {
      break;  // EIO once the child has closed the terminal
    }
  }
  ::close(master);
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << text;
  return text;
}

TEST(ProgressOutput, ProgressLineOnlyOnATerminal) {
  const auto dir = testing::scratch_dir();
  // Big enough that rendering takes longer than one redraw interval (100 ms).
  const std::vector<std::string> simulate = {"simulate", "--scene", "bumps",   "--width", "320",
                                             "--height", "320",     "--noise", "none"};
  const std::string drawn = run_on_terminal(with(simulate, {"--out", (dir / "tty").string()}));
  EXPECT_NE(drawn.find("\r\033[Ksimulate "), std::string::npos) << drawn;
  EXPECT_NE(drawn.find("/96 frames  ETA"), std::string::npos) << drawn;
  // The line is cleared at the end, so what follows (the log) starts on a clean line.
  const auto last_clear = drawn.rfind("\r\033[K");
  ASSERT_NE(last_clear, std::string::npos);
  EXPECT_EQ(drawn.find("ETA", last_clear), std::string::npos) << drawn;

  // A visible progress line is cleared even when the run is too short to draw it, so a short run
  // shows that --quiet and --json never make it visible.
  const std::vector<std::string> small = {"simulate", "--scene", "sphere", "--width", "32", "--height", "32"};

  const std::string quiet = run_on_terminal(with(small, {"--out", (dir / "tty-quiet").string(), "--quiet"}));
  EXPECT_EQ(quiet, "") << "--quiet draws no progress, even on a terminal";
  const std::string json = run_on_terminal(with(small, {"--out", (dir / "tty-json").string(), "--json"}));
  EXPECT_EQ(json.find('\r'), std::string::npos) << "--json draws no progress: " << json;
}

TEST(ProgressOutput, NaturalLightingStackSolvesWithShapePrior) {
  const auto dir = testing::scratch_dir();
  auto run =
      run_lightstage({"simulate", "--scene", "bunny", "--lighting", "natural", "--frames", "24", "--width",
                      "64", "--height", "64", "--seed", "5", "--out", (dir / "stack").string(), "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto j = one_json_object(run);
  expect_keys(j, {"stack", "frames", "lighting", "prior", "shape_prior_flags", "seconds", "total_seconds"});
  EXPECT_EQ(j.value("frames", 0), 24);
  EXPECT_EQ(j.value("lighting", ""), "natural");
  ASSERT_TRUE(std::filesystem::exists(dir / "stack/prior.pfm"));
  std::ifstream manifest_file(dir / "stack/manifest.json");
  const auto manifest = nlohmann::json::parse(manifest_file);
  EXPECT_TRUE(manifest.contains("natural_capture")) << manifest.dump();

  const auto& flags = j["shape_prior_flags"];
  ASSERT_TRUE(flags.contains("pixel_mm")) << flags.dump();
  run = run_lightstage({"solve", "--input", (dir / "stack").string(), "--method", "shape-prior", "--prior",
                        flags["prior"].get<std::string>(), "--pixel-mm",
                        fmt::format("{}", flags["pixel_mm"].get<double>()), "--out",
                        (dir / "result").string(), "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto solved = one_json_object(run);
  EXPECT_EQ(solved.value("method", ""), "shape-prior");
  // Random lighting, random responses and a beta-3 prior: about 4 degrees at this size (seed 5).
  EXPECT_LT(solved["error_vs_ground_truth"].value("mean_deg", 99.0), 8.0) << solved.dump();

  // The human line names the solve command to run.
  run = run_lightstage({"simulate", "--scene", "sphere", "--lighting", "natural", "--frames", "12", "--width",
                        "32", "--height", "32", "--out", (dir / "human").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("--method shape-prior --prior " + (dir / "human/prior.pfm").string()),
            std::string::npos)
      << run.out;
}

TEST(ProgressOutput, LightingFlagsOfTheOtherModeAreRefused) {
  const auto dir = testing::scratch_dir();
  auto run =
      run_lightstage({"simulate", "--lighting", "natural", "--noise", "none", "--out", (dir / "a").string()});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("--noise applies to --lighting dome only"), std::string::npos) << run.err;
  run = run_lightstage({"simulate", "--frames", "10", "--out", (dir / "b").string()});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("--frames applies to --lighting natural only"), std::string::npos) << run.err;
  run = run_lightstage(
      {"simulate", "--lighting", "natural", "--prior-beta", "9", "--out", (dir / "c").string()});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("--prior-beta"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace lightstage
