// A whole capture (capture_stack) against the scripted controller and camera
// of capture_fakes.hpp: what it refuses before taking anything, and what an
// interrupted one leaves in its folder.
#include "lightstage/host/capture/capture_session.hpp"

#include "capture_fakes.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/io/write_fault.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cerrno>

namespace lightstage {
namespace {

namespace fs = std::filesystem;
using testing::Bench;
using testing::device_error_of;

Rig rig_of(int leds, double max_on_us = 2'000'000) {
  Rig rig;
  rig.name = "session-test";
  for (int id = 1; id <= leds; ++id) {
    Led led;
    led.id = id;
    led.position_mm = Vec3(10.0 * id, 50, 300);
    led.relative_intensity = 1;
    led.limits.max_on_us = max_on_us;
    rig.leds.push_back(led);
  }
  rig.camera.exposure_us = 1000;
  rig.camera.gain = 1;
  return rig;
}

CaptureOptions fixed_exposure(const fs::path& out, double exposure_us, int dark_frames) {
  CaptureOptions options;
  options.out = out;
  options.exposure_us = exposure_us;
  options.dark_frames = dark_frames;
  options.mode = OutputMode::kQuiet;
  return options;
}

ImageStack load(const fs::path& dir) {
  io::LoadOptions options;
  options.min_images = 1;
  return io::load_stack(dir, options);
}

TEST(CaptureSession, AnExposureTooLongForAnLedIsRefusedBeforeAnyDarkIsTaken) {
  Bench bench;
  const fs::path out = testing::scratch_dir() / "capture";
  const std::string message = testing::error_of(
      [&] { capture_stack(rig_of(3, 100'000), *bench.client, bench.cam, fixed_exposure(out, 200'000, 2)); });
  EXPECT_NE(message.find("LED 1 at 200000 us"), std::string::npos) << message;
  EXPECT_EQ(bench.cam.triggers, 0);  // no dark, no frame
  EXPECT_FALSE(fs::exists(out / "manifest.json"));
}

TEST(CaptureSession, AWatchdogAbortKeepsTheFramesExposedBeforeIt) {
  Bench bench;
  bench.cam.hardware = true;
  bench.dome.watchdog_sequence = 0;
  bench.dome.watchdog_after = 6;
  const Rig rig = rig_of(12);
  const fs::path out = testing::scratch_dir() / "capture";
  const std::string message =
      device_error_of([&] { capture_stack(rig, *bench.client, bench.cam, fixed_exposure(out, 1000, 0)); });
  EXPECT_NE(message.find("WATCHDOG"), std::string::npos) << message;
  EXPECT_NE(message.find("the frames taken so far are kept"), std::string::npos) << message;
  const ImageStack stack = load(out);
  ASSERT_EQ(stack.frames.size(), 6u);
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(stack.frames[i].led_id, static_cast<int>(i) + 1);
    EXPECT_EQ(stack.frames[i].image.at<std::uint16_t>(0, 0), i + 1);
  }

  // --resume takes the other six only.
  CaptureOptions again = fixed_exposure(out, 1000, 0);
  again.resume = true;
  const CaptureReport report = capture_stack(rig, *bench.client, bench.cam, again);
  EXPECT_EQ(report.frames, 12u);
  EXPECT_EQ(report.taken_now, 6u);
  EXPECT_EQ(load(out).frames.size(), 12u);
}

TEST(CaptureSession, AFullDiskLeavesALoadableStackAndSaysHowToGoOn) {
  Bench bench;
  const Rig rig = rig_of(4);
  const fs::path out = testing::scratch_dir() / "capture";
  std::string message;
  {
    // Room for two frames' index, then the disk is full.
    std::atomic<int> manifests{0};
    const io::ScopedWriteFault full([&](const fs::path& target) {
      if (target.filename() != "manifest.json") return 0;
      return ++manifests > 4 ? ENOSPC : 0;  // the plan, the darks, frames 1 and 2
    });
    message =
        device_error_of([&] { capture_stack(rig, *bench.client, bench.cam, fixed_exposure(out, 1000, 1)); });
  }
  EXPECT_NE(message.find("no space left on the device (ENOSPC)"), std::string::npos) << message;
  EXPECT_NE(message.find("--resume"), std::string::npos) << message;
  EXPECT_EQ(load(out).frames.size(), 2u);

  CaptureOptions again = fixed_exposure(out, 1000, 1);
  again.resume = true;
  EXPECT_EQ(capture_stack(rig, *bench.client, bench.cam, again).frames, 4u);
  EXPECT_EQ(load(out).frames.size(), 4u);
}

TEST(CaptureSession, ResumeRefusesAChangedExposureOrDarkCount) {
  Bench bench;
  bench.cam.drop_all = true;  // no frame ever comes: the capture stops after planning
  const Rig rig = rig_of(2);
  const fs::path out = testing::scratch_dir() / "capture";
  CaptureOptions first = fixed_exposure(out, 1000, 0);
  first.max_retakes = 0;
  EXPECT_NE(device_error_of([&] { capture_stack(rig, *bench.client, bench.cam, first); }).find("no frame"),
            std::string::npos);
  bench.cam.drop_all = false;
  // Planned, nothing taken: the folder is an (empty) stack already.
  EXPECT_TRUE(fs::exists(out / "filenames.txt"));

  CaptureOptions changed = fixed_exposure(out, 2000, 0);
  changed.resume = true;
  EXPECT_NE(testing::error_of([&] {
              capture_stack(rig, *bench.client, bench.cam, changed);
            }).find("planned with --exposure-us 1000, this run asks for --exposure-us 2000"),
            std::string::npos);
  changed = fixed_exposure(out, 1000, 3);
  changed.resume = true;
  EXPECT_NE(testing::error_of([&] {
              capture_stack(rig, *bench.client, bench.cam, changed);
            }).find("planned with --dark-frames 0, this run asks for 3"),
            std::string::npos);
  EXPECT_EQ(bench.cam.triggers, 2);  // only the first run's one try of each LED
}

}  // namespace
}  // namespace lightstage
