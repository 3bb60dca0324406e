// Where the CLI writes: never over a capture or stack it did not make, never
// into the folder it reads, and a promised file that cannot be written fails the run.
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

namespace lightstage {
namespace {

namespace fs = std::filesystem;
using testing::run_lightstage;

std::vector<std::string> small_simulation(const fs::path& out) {
  return {"simulate", "--scene",  "sphere", "--lights", "distant",    "--width",
          "32",       "--height", "32",     "--out",    out.string(), "--quiet"};
}

std::string contents(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(OutputPaths, SimulateRefusesAFolderThatHoldsSomething) {
  const fs::path out = testing::scratch_dir() / "capture";
  fs::create_directories(out);
  std::ofstream(out / "001.png") << "a captured frame";
  std::ofstream(out / "notes.txt") << "mine";

  testing::RunResult run = run_lightstage(small_simulation(out));
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("not empty"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("--force"), std::string::npos) << run.err;
  EXPECT_EQ(contents(out / "001.png"), "a captured frame");
  EXPECT_FALSE(fs::exists(out / "filenames.txt"));

  // --force writes the stack over it and removes nothing it did not write.
  std::vector<std::string> forced = small_simulation(out);
  forced.push_back("--force");
  run = run_lightstage(forced);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(contents(out / "001.png"), "a captured frame");
  EXPECT_EQ(contents(out / "notes.txt"), "mine");
  EXPECT_TRUE(fs::exists(out / "filenames.txt"));
}

TEST(OutputPaths, SolveRefusesToWriteIntoItsInput) {
  const fs::path dir = testing::scratch_dir();
  const fs::path stack = dir / "stack";
  ASSERT_EQ(run_lightstage(small_simulation(stack)).exit_code, 0);
  // A frame whose name a solve output has (a DiLiGenT-style folder may hold any names).
  std::ofstream(stack / "normal.png") << "an input";
  fs::create_directory_symlink(stack, dir / "link");
  for (const fs::path& out : {stack, dir / "link", stack / ".", stack / "result"}) {
    const testing::RunResult run =
        run_lightstage({"solve", "--input", stack.string(), "--out", out.string(), "--quiet"});
    EXPECT_EQ(run.exit_code, 1) << out << run.err;
    EXPECT_NE(run.err.find("input folder"), std::string::npos) << run.err;
  }
  EXPECT_EQ(contents(stack / "normal.png"), "an input");
  EXPECT_FALSE(fs::exists(stack / "summary.json"));
}

TEST(OutputPaths, TheOtherFolderCommandsRefuseTheirInput) {
  const fs::path dir = testing::scratch_dir();
  const fs::path stack = dir / "stack";
  const fs::path result = dir / "result";
  ASSERT_EQ(run_lightstage(small_simulation(stack)).exit_code, 0);
  ASSERT_EQ(
      run_lightstage({"solve", "--input", stack.string(), "--out", result.string(), "--quiet"}).exit_code, 0);
  const std::vector<std::vector<std::string>> commands = {
      {"integrate", "--input", result.string(), "--out", result.string()},
      {"relight", "--input", result.string(), "--light", "0,0,1", "--out", (result / "relit").string()},
      {"reflectance", "--input", stack.string(), "--out", stack.string()},
      {"report", result.string(), "--out", (result / "normal.png").string()},
  };
  const std::string normal_before = contents(result / "normal.png");
  for (const auto& command : commands) {
    const testing::RunResult run = run_lightstage(command);
    EXPECT_EQ(run.exit_code, 1) << command.front() << ": " << run.err;
    EXPECT_NE(run.err.find("--out"), std::string::npos) << run.err;
  }
  EXPECT_EQ(contents(result / "normal.png"), normal_before);
  EXPECT_FALSE(fs::exists(result / "surface.json"));
  EXPECT_FALSE(fs::exists(stack / "reflectance.json"));
}

TEST(OutputPaths, SolveFailsWhenItsReportCannotBeWritten) {
  const fs::path dir = testing::scratch_dir();
  const fs::path stack = dir / "stack";
  ASSERT_EQ(run_lightstage(small_simulation(stack)).exit_code, 0);
  fs::create_directories(dir / "result" / "report.html");  // a folder where the file must go
  const testing::RunResult run =
      run_lightstage({"solve", "--input", stack.string(), "--out", (dir / "result").string(), "--quiet"});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find((dir / "result" / "report.html").string()), std::string::npos) << run.err;
  EXPECT_TRUE(fs::exists(dir / "result" / "normal.png"));  // the rest is kept
}

}  // namespace
}  // namespace lightstage
