// Bad input through the CLI: one line on stderr naming the file and what is
// wrong, a non-zero exit, and no crash.
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <fstream>

namespace lightstage {
namespace {

using testing::run_lightstage;

// A small valid stack to break in different ways.
std::filesystem::path make_stack(const std::filesystem::path& dir) {
  const auto stack = dir / "stack";
  const auto run = run_lightstage({"simulate", "--scene", "sphere", "--lights", "distant", "--width", "32",
                                   "--height", "32", "--out", stack.string()});
  EXPECT_EQ(run.exit_code, 0) << run.err;
  return stack;
}

void expect_one_line_error(const testing::RunResult& run, const std::string& needle) {
  EXPECT_EQ(run.exit_code, 1) << run.out << run.err;
  EXPECT_NE(run.err.find(needle), std::string::npos) << run.err;
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
}

testing::RunResult solve(const std::filesystem::path& stack) {
  return run_lightstage(
      {"solve", "--input", stack.string(), "--out", (stack.parent_path() / "out").string()});
}

TEST(BadInput, MissingStackFolder) { expect_one_line_error(solve(testing::scratch_dir() / "nope"), "nope"); }

TEST(BadInput, MissingImage) {
  const auto stack = make_stack(testing::scratch_dir());
  std::filesystem::remove(stack / "017.png");
  expect_one_line_error(solve(stack), "017.png");
}

TEST(BadInput, NonImageFile) {
  const auto stack = make_stack(testing::scratch_dir());
  std::ofstream(stack / "005.png") << "this is not a PNG";
  expect_one_line_error(solve(stack), "005.png");
}

TEST(BadInput, MismatchedImageSizes) {
  const auto dir = testing::scratch_dir();
  const auto stack = make_stack(dir);
  const auto other = dir / "other";
  ASSERT_EQ(run_lightstage({"simulate", "--lights", "distant", "--width", "40", "--height", "40", "--out",
                            other.string()})
                .exit_code,
            0);
  std::filesystem::copy_file(other / "003.png", stack / "003.png",
                             std::filesystem::copy_options::overwrite_existing);
  expect_one_line_error(solve(stack), "003.png");
}

TEST(BadInput, FewerThanThreeLights) {
  const auto stack = make_stack(testing::scratch_dir());
  std::ofstream(stack / "filenames.txt") << "001.png\n002.png\n";
  std::ofstream(stack / "light_directions.txt") << "0 0 1\n1 0 1\n";
  std::ofstream(stack / "light_intensities.txt") << "1 1 1\n1 1 1\n";
  std::filesystem::remove(stack / "manifest.json");
  expect_one_line_error(solve(stack), "filenames.txt");
}

TEST(BadInput, LightFileWithWrongCount) {
  const auto stack = make_stack(testing::scratch_dir());
  std::ofstream(stack / "light_directions.txt") << "0 0 1\n1 0 1\n0 1 1\n";
  expect_one_line_error(solve(stack), "light_directions.txt");
}

TEST(BadInput, MalformedLightLine) {
  const auto stack = make_stack(testing::scratch_dir());
  std::string text;
  for (int i = 0; i < 96; ++i) text += i == 41 ? "0 zero 1\n" : "0 0 1\n";
  std::ofstream(stack / "light_directions.txt") << text;
  const auto run = solve(stack);
  expect_one_line_error(run, "light_directions.txt");
  EXPECT_NE(run.err.find("42"), std::string::npos) << run.err;  // the 1-based line number
}

TEST(BadInput, EvalWithMissingPrediction) {
  const auto stack = make_stack(testing::scratch_dir());
  expect_one_line_error(
      run_lightstage({"eval", "--pred", (stack / "none.png").string(), "--gt", stack.string()}), "none.png");
}

TEST(BadInput, BadSolverOptionNamesTheFlag) {
  const auto stack = make_stack(testing::scratch_dir());
  const auto run = run_lightstage(
      {"solve", "--input", stack.string(), "--t-low", "1.5", "--out", (stack.parent_path() / "o").string()});
  expect_one_line_error(run, "t_low");
}

TEST(BadInput, ImageOutsideTheStackFolder) {
  const auto stack = make_stack(testing::scratch_dir());
  std::string text;
  for (int i = 1; i <= 96; ++i) text += i == 7 ? "../elsewhere.png\n" : fmt::format("{:03}.png\n", i);
  std::ofstream(stack / "filenames.txt") << text;
  const auto run = solve(stack);
  expect_one_line_error(run, "filenames.txt:7");
}

TEST(BadInput, EvalWithNothingToCompare) {
  // An all-zero normal map holds no normal: that is no result, not a 0-degree one.
  const auto stack = make_stack(testing::scratch_dir());
  const cv::Mat empty(32, 32, CV_16UC3, cv::Scalar::all(0));
  cv::imwrite((stack / "empty.png").string(), empty);
  expect_one_line_error(
      run_lightstage({"eval", "--pred", (stack / "empty.png").string(), "--gt", stack.string()}),
      "no pixel has both");
}

TEST(BadInput, SignalDependentNoiseNeedsLambda) {
  const auto run = run_lightstage(
      {"simulate", "--noise", "signal-dependent", "--out", (testing::scratch_dir() / "s").string()});
  expect_one_line_error(run, "--lambda");
}

TEST(BadInput, UnknownScene) {
  const auto run =
      run_lightstage({"simulate", "--scene", "teapot", "--out", testing::scratch_dir().string()});
  expect_one_line_error(run, "teapot");
}

}  // namespace
}  // namespace lightstage
