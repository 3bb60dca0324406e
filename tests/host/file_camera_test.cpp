// folder: cameras: files a tethering program writes, decoded into frames with
// their EXIF time and exposure (the simulated DSLR's DNGs stand in for a camera's).
#include "lightstage/host/capture/file_camera.hpp"

#include "lightstage/common/clock.hpp"
#include "lightstage/host/capture/folder_source.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/sim/dng_writer.hpp"
#include "lightstage/testing/paths.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <thread>

namespace lightstage {
namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;
using ::testing::HasSubstr;

// A DNG whose every site reads `level` above a black of 512 (white 16383), shot at `taken`.
void write_shot(const fs::path& path, double exposure_s, int level,
                std::chrono::system_clock::time_point taken = std::chrono::system_clock::now()) {
  sim::DngShot shot;
  shot.mosaic = cv::Mat(32, 48, CV_16UC1, cv::Scalar(512 + level));
  shot.black_level = {512, 512, 512, 512};
  shot.white_level = 16383;
  shot.exposure_s = exposure_s;
  shot.iso = 200;
  shot.taken = taken;
  sim::write_dng(path, shot);
}

camera::CameraUri folder_uri(const fs::path& dir) {
  return camera::parse_camera_uri("folder:" + dir.string());
}

std::unique_ptr<camera::Camera> open_folder(const fs::path& dir) {
  register_file_cameras();
  return camera::open_camera_uri("folder:" + dir.string() + "?poll_ms=5");
}

TEST(FolderSource, ReportsOnlyNewCompleteCameraFilesInTheOrderWritten) {
  const fs::path dir = testing::scratch_dir() / "shots";
  fs::create_directories(dir);
  write_shot(dir / "IMG_0001.DNG", 0.01, 100);  // an earlier run's shot
  auto source = open_folder_source(camera::parse_camera_uri("folder:" + dir.string() + "?poll_ms=5"));
  EXPECT_FALSE(source->software_trigger());
  source->start();
  EXPECT_FALSE(source->wait_file(milliseconds(30))) << "a file from before start() is not a new shot";
  std::ofstream(dir / "notes.txt") << "not an image";
  std::ofstream(dir / ".IMG_0002.DNG.tmp") << "half written";
  write_shot(dir / "IMG_0002.DNG", 0.01, 100);
  std::this_thread::sleep_for(milliseconds(20));
  write_shot(dir / "IMG_0003.DNG", 0.01, 100);
  const std::int64_t before = monotonic_now_ns();
  const auto first = source->wait_file(milliseconds(500));
  const auto second = source->wait_file(milliseconds(500));
  ASSERT_TRUE(first && second);
  EXPECT_EQ(first->path.filename(), "IMG_0002.DNG");
  EXPECT_EQ(second->path.filename(), "IMG_0003.DNG");
  EXPECT_LE(first->arrived_ns, monotonic_now_ns());
  EXPECT_GE(second->arrived_ns, before - 1'000'000'000);
  EXPECT_FALSE(source->wait_file(milliseconds(30)));
  EXPECT_THROW(source->trigger(), camera::CameraError);
}

TEST(FolderSource, RefusesAMissingFolderAndUnknownOptions) {
  const fs::path dir = testing::scratch_dir();
  EXPECT_THROW(open_folder_source(folder_uri(dir / "missing")), InputError);
  EXPECT_THROW(open_folder_source(camera::parse_camera_uri("folder:" + dir.string() + "?poll_ms=0")),
               InputError);
  EXPECT_THROW(open_folder_source(camera::parse_camera_uri("folder:" + dir.string() + "?wait=1")),
               InputError);
  try {
    open_folder_source(folder_uri(dir / "missing"));
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("missing"));
  }
}

TEST(FileCamera, DecodesEachShotLinearWithItsExifTimeAndExposure) {
  const fs::path dir = testing::scratch_dir() / "tether";
  fs::create_directories(dir);
  auto cam = open_folder(dir);
  EXPECT_THAT(cam->trigger_modes(), ::testing::ElementsAre(camera::TriggerMode::kHardware));
  camera::CameraConfig config = cam->default_config();
  ASSERT_EQ(cam->validate(config).status, camera::ConfigStatus::kValid);
  cam->configure(config);
  const camera::Controls now = cam->set_controls({10'000, std::nullopt});
  EXPECT_EQ(now.exposure_us, 10'000);
  cam->start();
  const auto taken = std::chrono::system_clock::time_point(std::chrono::milliseconds(1'700'000'000'123));
  write_shot(dir / "IMG_0001.DNG", 0.01, 7936, taken);
  const auto frame = cam->wait_frame(milliseconds(2000));
  ASSERT_TRUE(frame);
  // Half size, BGR, (raw − black) / (white − black) · 65535.
  EXPECT_EQ(frame->image.type(), CV_16UC3);
  EXPECT_EQ(frame->image.size(), cv::Size(24, 16));
  EXPECT_NEAR(frame->image.at<cv::Vec3w>(1, 1)[1], 7936.0 / (16383 - 512) * 65535, 1.0);
  EXPECT_TRUE(frame->own_clock);
  EXPECT_EQ(frame->clock, camera::ClockDomain::kRealtime);
  EXPECT_EQ(frame->timestamp_ns, 1'700'000'000'123'000'000);
  EXPECT_EQ(frame->timestamp_resolution_ns, 1'000'000);
  EXPECT_NEAR(frame->exposure_us, 10'000, 0.01);  // a rational in the file
  EXPECT_TRUE(frame->controls_reported);
  EXPECT_DOUBLE_EQ(frame->analogue_gain, 2.0);
  EXPECT_THAT(frame->source_file, HasSubstr("IMG_0001.DNG"));

  // A damaged file is skipped (its step is retaken); the next good one comes.
  std::ofstream(dir / "IMG_0002.DNG") << "not a raw file";
  write_shot(dir / "IMG_0003.DNG", 0.01, 100);
  const auto next = cam->wait_frame(milliseconds(2000));
  ASSERT_TRUE(next);
  EXPECT_THAT(next->source_file, HasSubstr("IMG_0003.DNG"));

  // The camera's dial at another speed than the capture asks: the frame says what the camera did
  // (the capture refuses it: capture_integration_test).
  write_shot(dir / "IMG_0004.DNG", 1.0 / 60, 100);
  const auto other = cam->wait_frame(milliseconds(2000));
  ASSERT_TRUE(other);
  EXPECT_NEAR(other->exposure_us, 1e6 / 60, 0.01);
  cam->stop();
}

TEST(FileCamera, RefusesTwoFilesPerShot) {
  // A camera set to RAW + an 8-bit image: the capture could not tell which file is which shot's.
  const fs::path dir = testing::scratch_dir() / "raw-and-png";
  fs::create_directories(dir);
  auto cam = open_folder(dir);
  cam->start();
  write_shot(dir / "IMG_0001.DNG", 0.01, 100);
  ASSERT_TRUE(cam->wait_frame(milliseconds(2000)));
  io::write_png(dir / "IMG_0001.PNG", cv::Mat(16, 24, CV_8UC3, cv::Scalar(10, 20, 30)));
  try {
    cam->wait_frame(milliseconds(2000));
    FAIL() << "a RAW and a PNG from one camera";
  } catch (const camera::CameraError& e) {
    EXPECT_THAT(e.what(), HasSubstr("RAW only"));
    EXPECT_THAT(e.what(), HasSubstr("IMG_0001.PNG"));
  }
}

TEST(FileCamera, IsFiredByItsRemotePortOnly) {
  const fs::path dir = testing::scratch_dir() / "remote";
  fs::create_directories(dir);
  auto cam = open_folder(dir);
  camera::CameraConfig config = cam->default_config();
  config.trigger = camera::TriggerMode::kSoftware;
  const camera::Validation v = cam->validate(config);
  EXPECT_EQ(v.status, camera::ConfigStatus::kInvalid);
  EXPECT_THAT(v.message(), HasSubstr("remote port"));
  register_file_cameras();
  EXPECT_THROW(camera::open_camera_uri("folder:" + dir.string() + "?fire=usb"), InputError);
  EXPECT_THROW(camera::open_camera_uri("folder:" + dir.string() + "?demosaic=quarter"), InputError);
}

// A camera the source can set (as gphoto2: does): what it was asked, and what it says it applied.
class SettableSource final : public camera::ShotSource {
 public:
  SettableSource() : ShotSource("test:settable") {}
  camera::CameraInfo info() const override { return {uri(), "settable", "test"}; }
  bool software_trigger() const override { return true; }
  camera::ShotSettings apply(const camera::ShotSettings& wanted) override {
    asked.push_back(wanted);
    camera::ShotSettings now = wanted;
    if (now.exposure_us) now.exposure_us = 1e6 / 125;  // the nearest speed it offers
    if (now.iso) now.iso = 400;
    return now;
  }
  void start() override {}
  void stop() override {}
  void trigger() override { ++triggers; }
  std::optional<camera::ArrivedFile> wait_file(std::chrono::milliseconds) override { return std::nullopt; }
  std::vector<camera::ShotSettings> asked;
  int triggers = 0;
};

TEST(FileCamera, SetsWhatItsSourceCanSetAndReportsWhatTheCameraApplied) {
  auto source = std::make_unique<SettableSource>();
  SettableSource& seen = *source;
  FileCameraOptions options;
  options.remote_port = false;
  options.settings.f_number = 8;
  options.settings.iso = 320;
  options.settings.image_format = "RAW";
  auto cam = make_file_camera(std::move(source), options);
  EXPECT_THAT(cam->trigger_modes(), ::testing::ElementsAre(camera::TriggerMode::kSoftware));
  camera::CameraConfig config = cam->default_config();
  cam->configure(config);
  cam->start();
  ASSERT_EQ(seen.asked.size(), 1u);
  EXPECT_EQ(seen.asked[0].f_number, 8);
  EXPECT_EQ(seen.asked[0].image_format, "RAW");
  const camera::Controls now = cam->set_controls({10'000, std::nullopt});
  EXPECT_DOUBLE_EQ(*now.exposure_us, 8'000);  // 1/125 s: what the camera took, not what was asked
  EXPECT_DOUBLE_EQ(*now.analogue_gain, 4.0);  // ISO 400 from the start
  cam->trigger();
  EXPECT_EQ(seen.triggers, 1);
  register_file_cameras();
  EXPECT_THROW(camera::open_camera_uri("folder:" + testing::scratch_dir().string() + "?aperture=8"),
               InputError);
}

}  // namespace
}  // namespace lightstage
