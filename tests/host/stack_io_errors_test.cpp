// Every way a stack folder can be broken gives one InputError line that names
// the file (and line or field) at fault.
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/testing/paths.hpp"
#include "stack_fixture.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <fstream>

namespace lightstage {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

class HostBrokenStack : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::scratch_dir() / "stack";
    io::write_stack(dir_, testing::small_stack(4));
  }

  void write(const std::string& name, const std::string& text) const { std::ofstream(dir_ / name) << text; }

  // The message of the InputError that loading gives (fails the test if none).
  std::string load_error() const {
    try {
      io::load_stack(dir_);
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
      return message;
    }
    ADD_FAILURE() << "the broken stack loaded";
    return {};
  }

  fs::path dir_;
};

TEST_F(HostBrokenStack, TheIntactStackLoads) { EXPECT_NO_THROW(io::load_stack(dir_)); }

TEST_F(HostBrokenStack, MissingFolder) {
  dir_ /= "nope";
  EXPECT_THAT(load_error(), HasSubstr("nope: no such stack folder"));
}

TEST_F(HostBrokenStack, FolderIsAFile) {
  dir_ /= "img_00.png";
  EXPECT_THAT(load_error(), HasSubstr("img_00.png: not a folder"));
}

TEST_F(HostBrokenStack, MissingFilenames) {
  fs::remove(dir_ / "filenames.txt");
  EXPECT_THAT(load_error(), HasSubstr("filenames.txt: no such file"));
}

TEST_F(HostBrokenStack, MissingLightDirections) {
  fs::remove(dir_ / "light_directions.txt");
  EXPECT_THAT(load_error(), HasSubstr("light_directions.txt: no such file"));
}

TEST_F(HostBrokenStack, ListedImageMissing) {
  fs::remove(dir_ / "img_02.png");
  EXPECT_THAT(load_error(), HasSubstr("img_02.png: no such file"));
}

TEST_F(HostBrokenStack, ListedFileIsNotAnImage) {
  write("img_01.png", "plain text\n");
  EXPECT_THAT(load_error(), HasSubstr("img_01.png: not a readable image"));
}

TEST_F(HostBrokenStack, ImageOfAnotherSize) {
  ASSERT_TRUE(cv::imwrite((dir_ / "img_03.png").string(), cv::Mat(5, 5, CV_16UC3, cv::Scalar::all(9))));
  EXPECT_THAT(load_error(), HasSubstr("img_03.png: image is 5x5, but img_00.png is 9x6"));
}

TEST_F(HostBrokenStack, ImageOfAnotherType) {
  ASSERT_TRUE(cv::imwrite((dir_ / "img_02.png").string(), cv::Mat(6, 9, CV_8UC3, cv::Scalar::all(9))));
  EXPECT_THAT(load_error(), HasSubstr("img_02.png: image is 8-bit RGB, but img_00.png is 16-bit RGB"));
}

TEST_F(HostBrokenStack, FewerThanThreeImages) {
  write("filenames.txt", "img_00.png\nimg_01.png\n");
  EXPECT_THAT(load_error(), HasSubstr("filenames.txt: 2 image(s) listed, at least 3 needed"));
}

TEST_F(HostBrokenStack, DirectionsWrongCount) {
  write("light_directions.txt", "0 0 1\n0 0.5 0.8\n0.5 0 0.8\n");
  EXPECT_THAT(load_error(),
              HasSubstr("light_directions.txt: 3 direction line(s), but filenames.txt lists 4"));
}

TEST_F(HostBrokenStack, DirectionsMalformedNumber) {
  write("light_directions.txt", "0 0 1\n0 0.5x 0.8\n0.5 0 0.8\n0.1 0.1 0.9\n");
  EXPECT_THAT(load_error(), HasSubstr("light_directions.txt:2: expected three numbers"));
}

TEST_F(HostBrokenStack, DirectionsTooFewColumns) {
  write("light_directions.txt", "0 0 1\n0 0.5 0.8\n0.5 0.8\n0.1 0.1 0.9\n");
  EXPECT_THAT(load_error(), HasSubstr("light_directions.txt:3: expected three numbers"));
}

TEST_F(HostBrokenStack, ZeroLengthDirection) {
  write("light_directions.txt", "0 0 1\n0 0.5 0.8\n0.5 0 0.8\n0 0 0\n");
  EXPECT_THAT(load_error(), HasSubstr("light_directions.txt:4: zero-length light direction"));
}

TEST_F(HostBrokenStack, IntensitiesWrongCount) {
  write("light_intensities.txt", "1 1 1\n1 1 1\n1 1 1\n1 1 1\n1 1 1\n");
  EXPECT_THAT(load_error(), HasSubstr("light_intensities.txt: 5 intensity line(s)"));
}

TEST_F(HostBrokenStack, IntensitiesMalformed) {
  write("light_intensities.txt", "1 1 1\n1 1 one\n1 1 1\n1 1 1\n");
  EXPECT_THAT(load_error(), HasSubstr("light_intensities.txt:2: expected three numbers"));
}

TEST_F(HostBrokenStack, IntensityNotPositive) {
  write("light_intensities.txt", "1 1 1\n1 1 1\n1 0 1\n1 1 1\n");
  EXPECT_THAT(load_error(), HasSubstr("light_intensities.txt:3: light intensities must be positive"));
}

TEST_F(HostBrokenStack, MaskOfAnotherSize) {
  ASSERT_TRUE(cv::imwrite((dir_ / "mask.png").string(), cv::Mat(4, 4, CV_8UC1, cv::Scalar::all(255))));
  EXPECT_THAT(load_error(), HasSubstr("mask.png: mask is 4x4, images are 9x6"));
}

TEST_F(HostBrokenStack, MaskAllZero) {
  ASSERT_TRUE(cv::imwrite((dir_ / "mask.png").string(), cv::Mat(6, 9, CV_8UC1, cv::Scalar::all(0))));
  EXPECT_THAT(load_error(), HasSubstr("mask.png: mask is empty"));
}

TEST_F(HostBrokenStack, GroundTruthOfAnotherSize) {
  ASSERT_TRUE(
      cv::imwrite((dir_ / "Normal_gt.png").string(), cv::Mat(3, 3, CV_16UC3, cv::Scalar::all(30000))));
  EXPECT_THAT(load_error(), HasSubstr("Normal_gt.png: ground truth is 3x3"));
}

TEST_F(HostBrokenStack, ManifestNotJson) {
  write("manifest.json", "{ not json");
  EXPECT_THAT(load_error(), HasSubstr("manifest.json: not valid JSON"));
}

TEST_F(HostBrokenStack, ManifestFrameCountDisagrees) {
  write("manifest.json", R"({"format": "lightstage-stack", "version": 1, "frames": [{}, {}]})");
  EXPECT_THAT(load_error(), HasSubstr("manifest.json: frames: 2 entries, but filenames.txt lists 4"));
}

TEST_F(HostBrokenStack, ManifestFieldOfWrongType) {
  write("manifest.json", R"({"frames": [{}, {"gain": "high"}, {}, {}]})");
  EXPECT_THAT(load_error(), HasSubstr("manifest.json: frames[1].gain: expected a number"));
}

TEST_F(HostBrokenStack, ManifestFileNameDisagrees) {
  write("manifest.json", R"({"frames": [{}, {}, {"file": "other.png"}, {}]})");
  EXPECT_THAT(load_error(), HasSubstr("manifest.json: frames[2].file"));
}

TEST_F(HostBrokenStack, ManifestOfAnotherFormat) {
  write("manifest.json", R"({"format": "something-else"})");
  EXPECT_THAT(load_error(), HasSubstr("manifest.json: format"));
}

TEST_F(HostBrokenStack, ManifestDarkMissing) {
  write("manifest.json", R"({"frames": [{}, {"dark": "dark_500us.png"}, {}, {}]})");
  EXPECT_THAT(load_error(), HasSubstr("manifest.json: frames[1].dark: 'dark_500us.png' is not in the stack"));
}

TEST_F(HostBrokenStack, ManifestDarkOfWrongType) {
  write("manifest.json", R"({"frames": [{}, {}, {"dark": 500}, {}]})");
  EXPECT_THAT(load_error(), HasSubstr("manifest.json: frames[2].dark: expected a file name"));
}

TEST_F(HostBrokenStack, ManifestDarkOutsideTheFolder) {
  write("manifest.json", R"({"frames": [{"dark": "../dark.png"}, {}, {}, {}]})");
  EXPECT_THAT(load_error(),
              HasSubstr("manifest.json: frames[0].dark: '../dark.png' must name a file inside"));
}

TEST_F(HostBrokenStack, ManifestDarkOfAnotherSize) {
  ASSERT_TRUE(cv::imwrite((dir_ / "dark.png").string(), cv::Mat(3, 3, CV_16UC3, cv::Scalar::all(300))));
  write("manifest.json", R"({"frames": [{}, {}, {}, {"dark": "dark.png"}]})");
  EXPECT_THAT(load_error(), HasSubstr("dark.png: dark frame is 3x3"));
}

}  // namespace
}  // namespace lightstage
