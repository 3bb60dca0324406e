#include "lightstage/host/progress.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <thread>
#include <vector>

namespace lightstage {
namespace {

using namespace std::chrono_literals;

TEST(Progress, LineShowsShareCountAndEstimate) {
  Progress p("solve", 200, "px", OutputMode::kHuman, nullptr);
  EXPECT_FALSE(p.visible());
  p.advance(50);
  EXPECT_EQ(p.line(2s), "solve   25% 50/200 px  ETA 6.0 s");
  p.advance(150);
  EXPECT_EQ(p.line(8s), "solve  100% 200/200 px  ETA 0.0 s");
}

TEST(Progress, NoEstimateBeforeThereIsARate) {
  Progress p("capture", 96, "frames", OutputMode::kHuman, nullptr);
  EXPECT_EQ(p.line(0s), "capture    0% 0/96 frames  ETA --");
  Progress unknown("render", 0, "frames", OutputMode::kHuman, nullptr);
  unknown.advance(3);
  EXPECT_EQ(unknown.line(90s), "render  3 frames  1m30s");
}

TEST(Progress, SilentWhenNotATerminalOrQuietOrJson) {
  std::FILE* file = std::tmpfile();
  ASSERT_NE(file, nullptr);
  for (const OutputMode mode : {OutputMode::kHuman, OutputMode::kQuiet, OutputMode::kJson}) {
    Progress p("x", 10, "items", mode, file);
    EXPECT_FALSE(p.visible());
    p.advance(10);
  }
  EXPECT_EQ(std::ftell(file), 0) << "progress written to a file";
  std::fclose(file);
}

TEST(Progress, CountsFromManyThreads) {
  Progress p("x", 8000, "items", OutputMode::kQuiet, nullptr);
  std::vector<std::thread> workers;
  for (int t = 0; t < 8; ++t) {
    workers.emplace_back([&] {
      for (int i = 0; i < 1000; ++i) p.advance();
    });
  }
  for (auto& w : workers) w.join();
  EXPECT_EQ(p.done(), 8000u);
}

}  // namespace
}  // namespace lightstage
