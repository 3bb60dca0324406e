// gphoto2: the settings' text and the download files without a camera, and
// the real libgphoto2 with no camera attached: enumeration, the errors of
// opening, and a real camera object from libgphoto2's "Directory Browse"
// driver on a disk: port (a camera with no settings and no capture).
#include "lightstage/hw/gphoto2_source.hpp"
#include "download_file.hpp"
#include "gphoto2_leaks.hpp"
#include "gphoto2_settings.hpp"
#include "lightstage/common/camera.hpp"
#include "lightstage/hw/backends.hpp"
#include "lightstage/testing/paths.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

namespace lightstage::hw {
namespace {

using camera::CameraError;
using ::testing::HasSubstr;
namespace g2 = gphoto2;

// ---------------------------------------------------------------------------
// The settings' text

TEST(Gphoto2Settings, ShutterTextsReadAsMicroseconds) {
  EXPECT_DOUBLE_EQ(*g2::parse_shutter_us("1/8000"), 125);
  EXPECT_NEAR(*g2::parse_shutter_us("1/3"), 1e6 / 3, 1e-6);
  EXPECT_DOUBLE_EQ(*g2::parse_shutter_us("0.3"), 300000);
  EXPECT_DOUBLE_EQ(*g2::parse_shutter_us("1\""), 1e6);
  EXPECT_DOUBLE_EQ(*g2::parse_shutter_us("1\"3"), 1.3e6);
  EXPECT_DOUBLE_EQ(*g2::parse_shutter_us("30"), 30e6);
  EXPECT_DOUBLE_EQ(*g2::parse_shutter_us("30\""), 30e6);
  EXPECT_DOUBLE_EQ(*g2::parse_shutter_us("1/125s"), 8000);
  EXPECT_DOUBLE_EQ(*g2::parse_shutter_us(" 2 sec "), 2e6);
  EXPECT_DOUBLE_EQ(*g2::parse_shutter_us("10/13"), 1e6 * 10 / 13);
}

TEST(Gphoto2Settings, ShutterTextsThatAreNoDurationAreRefused) {
  for (const char* text :
       {"bulb", "Bulb", "BULB", "Time", "auto", "Auto", "", "x 200", "1/0", "-1", "0", "1\"", "\"3"}) {
    if (std::string_view(text) == "1\"") continue;  // a whole second, read above
    EXPECT_FALSE(g2::parse_shutter_us(text)) << text;
  }
}

TEST(Gphoto2Settings, NearestShutterInLogSpaceNeverBulb) {
  const std::vector<std::string> choices = {"bulb", "30", "15", "1", "0.5", "1/3", "1/125", "1/8000"};
  auto nearest = [&](double us) {
    return g2::nearest_choice(choices, us, g2::parse_shutter_us, g2::max_log2_ratio(g2::Setting::kShutter));
  };
  EXPECT_EQ(nearest(8000), 6u);
  EXPECT_EQ(nearest(300000), 5u);  // 1/3 is 0.15 stop away, 0.5 is 0.74
  EXPECT_EQ(nearest(100), 7u);     // 1/10000 s: 1/8000 is a third of a stop away
  EXPECT_FALSE(nearest(1e9));      // 1000 s: 30 s is five stops short
  EXPECT_FALSE(nearest(20));       // 1/50000 s
  EXPECT_FALSE(nearest(-5));
  EXPECT_FALSE(g2::nearest_choice({"bulb", "auto"}, 8000, g2::parse_shutter_us, 0.5));
}

TEST(Gphoto2Settings, ApertureTexts) {
  EXPECT_DOUBLE_EQ(*g2::parse_f_number("f/5.6"), 5.6);
  EXPECT_DOUBLE_EQ(*g2::parse_f_number("F8"), 8);
  EXPECT_DOUBLE_EQ(*g2::parse_f_number("8"), 8);
  EXPECT_DOUBLE_EQ(*g2::parse_f_number("f/8.0"), 8);
  EXPECT_FALSE(g2::parse_f_number("implicit auto"));
  EXPECT_FALSE(g2::parse_f_number("---"));
  const std::vector<std::string> choices = {"implicit auto", "f/4", "f/5.6", "f/8"};
  const double max = g2::max_log2_ratio(g2::Setting::kAperture);
  EXPECT_EQ(g2::nearest_choice(choices, 6.3, g2::parse_f_number, max), 2u);
  EXPECT_FALSE(g2::nearest_choice(choices, 22, g2::parse_f_number, max));
}

TEST(Gphoto2Settings, IsoTextsAndAutoRefused) {
  EXPECT_DOUBLE_EQ(*g2::parse_iso("100"), 100);
  EXPECT_DOUBLE_EQ(*g2::parse_iso("ISO 400"), 400);
  for (const char* text : {"Auto", "AUTO", "Auto ISO", "Hi 1", "L 1.0", ""})
    EXPECT_FALSE(g2::parse_iso(text)) << text;
  const std::vector<std::string> choices = {"Auto", "100", "200", "400"};
  const double max = g2::max_log2_ratio(g2::Setting::kIso);
  EXPECT_EQ(g2::nearest_choice(choices, 250, g2::parse_iso, max), 2u);
  EXPECT_FALSE(g2::nearest_choice(choices, 50, g2::parse_iso, max));  // a stop below the lowest
}

TEST(Gphoto2Settings, FormatByNameAndMemoryCard) {
  EXPECT_EQ(g2::choice_by_name({"Large Fine JPEG", "RAW + Large Fine JPEG", "RAW"}, "raw"), 2u);
  EXPECT_EQ(g2::choice_by_name({"Large Fine JPEG", "RAW + Large Fine JPEG"}, "RAW"), 1u);
  EXPECT_FALSE(g2::choice_by_name({"Large Fine JPEG", "RAW"}, "TIFF"));
  EXPECT_FALSE(g2::choice_by_name({"RAW"}, " "));
  EXPECT_EQ(g2::memory_card_choice({"Internal RAM", "Memory card"}), 1u);
  EXPECT_EQ(g2::memory_card_choice({"sdram", "card"}), 1u);
  EXPECT_FALSE(g2::memory_card_choice({"Internal RAM"}));
}

TEST(Gphoto2Settings, WidgetNamesAndDescriptions) {
  EXPECT_EQ(g2::widget_names(g2::Setting::kShutter).front(), "shutterspeed");
  EXPECT_EQ(g2::widget_names(g2::Setting::kIso).size(), 2u);
  EXPECT_EQ(g2::describe_shutter_us(125), "1/8000 s");
  EXPECT_EQ(g2::describe_shutter_us(300000), "0.3 s");
  EXPECT_EQ(g2::describe_shutter_us(2e6), "2 s");
  std::vector<std::string> many;
  for (int i = 0; i < 20; ++i) many.push_back(std::to_string(i));
  EXPECT_EQ(g2::describe_choices(many), "0, 1, 2, 3, 4, 5, ..., 14, 15, 16, 17, 18, 19");
  EXPECT_EQ(g2::describe_choices({}), "none");
}

// ---------------------------------------------------------------------------
// The download files

std::string read_all(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_text(int fd, std::string_view text) {
  ASSERT_EQ(::write(fd, text.data(), text.size()), static_cast<ssize_t>(text.size()));
}

std::size_t entries(const std::filesystem::path& dir) {
  return static_cast<std::size_t>(std::distance(std::filesystem::directory_iterator(dir), {}));
}

TEST(DownloadFile, KeepsTheNameAndNeverOverwrites) {
  const auto dir = lightstage::testing::scratch_dir();
  const auto first =
      write_new_file(dir, "IMG_0001.CR2", "gphoto2:test", [](int fd) { write_text(fd, "one"); });
  const auto second =
      write_new_file(dir, "IMG_0001.CR2", "gphoto2:test", [](int fd) { write_text(fd, "two"); });
  const auto third =
      write_new_file(dir, "IMG_0001.CR2", "gphoto2:test", [](int fd) { write_text(fd, "three"); });
  EXPECT_EQ(first, dir / "IMG_0001.CR2");
  EXPECT_EQ(second, dir / "IMG_0001-1.CR2");
  EXPECT_EQ(third, dir / "IMG_0001-2.CR2");
  EXPECT_EQ(read_all(first), "one");
  EXPECT_EQ(read_all(second), "two");
  EXPECT_EQ(read_all(third), "three");
  EXPECT_EQ(entries(dir), 3u);  // no temporary file left beside them
}

TEST(DownloadFile, ACameraPathLandsInTheFolder) {
  const auto dir = lightstage::testing::scratch_dir();
  EXPECT_EQ(write_new_file(dir, "../../etc/passwd", "gphoto2:test", [](int fd) { write_text(fd, "x"); }),
            dir / "passwd");
  EXPECT_EQ(write_new_file(dir, "..", "gphoto2:test", [](int fd) { write_text(fd, "x"); }), dir / "shot");
}

TEST(DownloadFile, AFailedDownloadLeavesNothing) {
  const auto dir = lightstage::testing::scratch_dir();
  EXPECT_THROW(write_new_file(dir, "IMG_0002.NEF", "gphoto2:test",
                              [](int fd) {
                                write_text(fd, "half");
                                throw CameraError(CameraError::Kind::kDisconnected, "gone");
                              }),
               CameraError);
  EXPECT_EQ(entries(dir), 0u);
}

TEST(DownloadFile, TheFolderMustExistAndBeWritable) {
  const auto dir = lightstage::testing::scratch_dir();
  try {
    check_download_dir(dir / "missing", "gphoto2:x");
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_THAT(e.what(), HasSubstr((dir / "missing").string()));
    EXPECT_THAT(e.what(), HasSubstr("does not exist"));
  }
  std::ofstream(dir / "file") << "x";
  EXPECT_THROW(check_download_dir(dir / "file", "gphoto2:x"), CameraError);
  EXPECT_NO_THROW(check_download_dir(dir, "gphoto2:x"));
}

TEST(DownloadFile, AFolderWithoutWritePermissionIsRefused) {
  if (::geteuid() == 0) GTEST_SKIP() << "root writes into any folder";
  const auto dir = lightstage::testing::scratch_dir();
  std::filesystem::create_directory(dir / "locked");
  std::filesystem::permissions(dir / "locked",
                               std::filesystem::perms::owner_read | std::filesystem::perms::owner_exec);
  try {
    check_download_dir(dir / "locked", "gphoto2:x");
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_THAT(e.what(), HasSubstr((dir / "locked").string()));
  }
  std::filesystem::permissions(dir / "locked", std::filesystem::perms::owner_all);
}

// ---------------------------------------------------------------------------
// libgphoto2 with no camera attached

camera::CameraError::Kind kind_of_open(const std::string& uri, const std::filesystem::path& dir,
                                       std::string* message) {
  try {
    open_gphoto2_source(camera::parse_camera_uri(uri), dir);
  } catch (const CameraError& e) {
    *message = e.what();
    return e.kind();
  }
  ADD_FAILURE() << "opened " << uri;
  return CameraError::Kind::kFailed;
}

class Gphoto2Library : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!backend_built("gphoto2")) GTEST_SKIP() << "built without libgphoto2";
    dir_ = lightstage::testing::scratch_dir();
  }
  bool camera_attached() const { return !list_gphoto2_cameras().empty(); }
  std::filesystem::path dir_;
};

TEST_F(Gphoto2Library, ListsNothingWithoutACamera) {
  const auto cameras = list_gphoto2_cameras();  // never throws
  for (const auto& c : cameras) {
    EXPECT_EQ(c.uri.rfind("gphoto2:", 0), 0u) << c.uri;
    EXPECT_THAT(c.driver, HasSubstr("libgphoto2 "));
  }
  if (!cameras.empty()) GTEST_SKIP() << "a camera is attached: " << cameras.front().uri;
}

TEST_F(Gphoto2Library, TheFirstCameraWhenThereIsNone) {
  if (camera_attached()) GTEST_SKIP() << "a camera is attached";
  std::string message;
  EXPECT_EQ(kind_of_open("gphoto2:", dir_, &message), CameraError::Kind::kNotFound);
  EXPECT_THAT(message, HasSubstr("gphoto2:"));
  EXPECT_THAT(message, HasSubstr("detects no camera"));
}

TEST_F(Gphoto2Library, AModelThatIsNotAttachedIsNotFound) {
  if (camera_attached()) GTEST_SKIP() << "a camera is attached";
  std::string message;
  EXPECT_EQ(kind_of_open("gphoto2:Canon EOS 5D Mark IV", dir_, &message), CameraError::Kind::kNotFound);
  EXPECT_THAT(message, HasSubstr("gphoto2:Canon EOS 5D Mark IV"));
  EXPECT_THAT(message, HasSubstr("no camera of model"));
}

TEST_F(Gphoto2Library, PortsThatHoldNoCamera) {
  std::string message;
  EXPECT_EQ(kind_of_open("gphoto2:usb:001,099", dir_, &message), CameraError::Kind::kNotFound);
  EXPECT_THAT(message, HasSubstr("no camera on port 'usb:001,099'"));
  EXPECT_EQ(kind_of_open("gphoto2:bogus:port?model=Canon EOS 5D Mark IV", dir_, &message),
            CameraError::Kind::kNotFound);
  EXPECT_THAT(message, HasSubstr("gphoto2:bogus:port"));
  EXPECT_THAT(message, HasSubstr("find port 'bogus:port'"));
  EXPECT_EQ(kind_of_open("gphoto2:disk:/tmp?model=No Such Camera 9000", dir_, &message),
            CameraError::Kind::kNotFound);
  EXPECT_THAT(message, HasSubstr("No Such Camera 9000"));
}

TEST_F(Gphoto2Library, TheDownloadFolderIsCheckedFirst) {
  std::string message;
  EXPECT_EQ(kind_of_open("gphoto2:", dir_ / "nowhere", &message), CameraError::Kind::kFailed);
  EXPECT_THAT(message, HasSubstr((dir_ / "nowhere").string()));
  EXPECT_EQ(kind_of_open("gphoto2:?download=" + (dir_ / "elsewhere").string(), dir_, &message),
            CameraError::Kind::kFailed);
  EXPECT_THAT(message, HasSubstr((dir_ / "elsewhere").string()));
}

TEST_F(Gphoto2Library, UnknownOptionsAreInputErrors) {
  EXPECT_THROW(open_gphoto2_source(camera::parse_camera_uri("gphoto2:?shutter=1"), dir_), InputError);
}

// libgphoto2's "Directory Browse" driver turns a folder (a disk: port) into a
// camera: opened, closed and asked for files through the real library, but
// with no settings, no capture and no events.
class DirectoryCamera : public Gphoto2Library {
 protected:
  void SetUp() override {
    Gphoto2Library::SetUp();
    if (IsSkipped()) return;
    card_ = dir_ / "card";
    std::filesystem::create_directories(card_ / "DCIM");
    std::ofstream(card_ / "DCIM" / "IMG_0001.JPG") << "jpeg";
    downloads_ = dir_ / "downloads";
    std::filesystem::create_directories(downloads_);
    uri_ = "gphoto2:disk:" + card_.string() + "?model=Directory Browse";
    source_ = open_gphoto2_source(camera::parse_camera_uri(uri_), downloads_);
  }
  std::filesystem::path card_, downloads_;
  std::string uri_;
  std::unique_ptr<camera::ShotSource> source_;
};

TEST_F(DirectoryCamera, OpensThroughTheLibrary) {
  EXPECT_EQ(source_->uri(), uri_);
  EXPECT_EQ(source_->info().model, "Directory Browse");
  EXPECT_EQ(source_->info().driver, "libgphoto2 disk:" + card_.string());
  EXPECT_TRUE(source_->software_trigger());
}

TEST_F(DirectoryCamera, ApplyReportsNothingAndRefusesWhatTheCameraLacks) {
  const camera::ShotSettings now = source_->apply({});
  EXPECT_FALSE(now.exposure_us);
  EXPECT_FALSE(now.image_format);
  try {
    camera::ShotSettings wanted;
    wanted.exposure_us = 8000;
    source_->apply(wanted);
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_EQ(e.kind(), CameraError::Kind::kUnsupported);
    EXPECT_THAT(e.what(), HasSubstr(uri_));
    EXPECT_THAT(e.what(), HasSubstr("shutter speed"));
    EXPECT_THAT(e.what(), HasSubstr("no settings"));
  }
  try {
    camera::ShotSettings wanted;
    wanted.image_format = "RAW";
    source_->apply(wanted);
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_EQ(e.kind(), CameraError::Kind::kUnsupported);
    EXPECT_THAT(e.what(), HasSubstr("image format"));
  }
}

TEST_F(DirectoryCamera, CaptureRefusedSaysWhatToSetOnTheCamera) {
  EXPECT_THROW(source_->trigger(), CameraError);  // before start()
  source_->start();
  try {
    source_->trigger();
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_EQ(e.kind(), CameraError::Kind::kUnsupported);
    EXPECT_THAT(e.what(), HasSubstr(uri_ + ": capture"));
    EXPECT_THAT(e.what(), HasSubstr("mode dial to M"));
  }
  try {
    source_->wait_file(std::chrono::milliseconds(10));
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_EQ(e.kind(), CameraError::Kind::kUnsupported);
    EXPECT_THAT(e.what(), HasSubstr("no new files"));
  }
  source_->stop();
  source_->stop();  // idempotent
  EXPECT_THROW(source_->wait_file(std::chrono::milliseconds(1)), CameraError);
}

}  // namespace
}  // namespace lightstage::hw
