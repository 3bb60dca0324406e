#include "lightstage/host/io/image_io.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <fstream>
#include <string>
#include <vector>

namespace lightstage {
namespace {

using ::testing::HasSubstr;

using testing::error_of;

cv::Mat ramp(int type, int rows = 7, int cols = 9) {
  cv::Mat image(rows, cols, type);
  cv::randu(image, 0, image.depth() == CV_8U ? 256 : 65536);
  return image;
}

TEST(HostImageIo, Png16RoundTripsGreyAndColour) {
  const auto dir = testing::scratch_dir();
  for (const int type : {CV_16UC1, CV_16UC3, CV_8UC1, CV_8UC3}) {
    const cv::Mat image = ramp(type);
    const auto path = dir / fmt::format("t{}.png", type);
    io::write_png(path, image);
    const cv::Mat back = io::read_image(path);
    ASSERT_EQ(back.type(), type);
    EXPECT_EQ(cv::norm(back, image, cv::NORM_INF), 0) << type;
  }
}

TEST(HostImageIo, WritesAtomicallyLeavingNoTemporaryFiles) {
  const auto dir = testing::scratch_dir();
  io::write_png16(dir / "a.png", ramp(CV_16UC3));
  io::write_png16(dir / "a.png", ramp(CV_16UC3));  // overwrite
  int files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 1);
}

TEST(HostImageIo, Png16RefusesOtherDepths) {
  const auto dir = testing::scratch_dir();
  EXPECT_THAT(error_of([&] { io::write_png16(dir / "x.png", ramp(CV_8UC3)); }), HasSubstr("x.png"));
  EXPECT_THAT(error_of([&] { io::write_png(dir / "f.png", cv::Mat(3, 3, CV_32FC1, 0.5)); }),
              HasSubstr("f.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
}

TEST(HostImageIo, WriteIntoMissingFolderNamesTheFile) {
  const auto dir = testing::scratch_dir() / "not" / "there";
  EXPECT_THAT(error_of([&] { io::write_png16(dir / "y.png", ramp(CV_16UC1)); }), HasSubstr("y.png"));
}

TEST(HostImageIo, MissingAndNonImageFilesAreInputErrors) {
  const auto dir = testing::scratch_dir();
  EXPECT_THAT(error_of([&] { io::read_image(dir / "missing.png"); }), HasSubstr("missing.png: no such file"));
  std::ofstream(dir / "text.png") << "this is not a PNG\n";
  EXPECT_THAT(error_of([&] { io::read_image(dir / "text.png"); }),
              HasSubstr("text.png: not a readable image"));
  std::filesystem::create_directory(dir / "folder.png");
  EXPECT_THAT(error_of([&] { io::read_image(dir / "folder.png"); }), HasSubstr("folder.png"));
}

TEST(HostImageIo, AlphaChannelIsDropped) {
  const auto dir = testing::scratch_dir();
  cv::Mat bgra(4, 5, CV_16UC4, cv::Scalar(1000, 2000, 3000, 65535));
  ASSERT_TRUE(cv::imwrite((dir / "alpha.png").string(), bgra));
  const cv::Mat back = io::read_image(dir / "alpha.png");
  ASSERT_EQ(back.type(), CV_16UC3);
  EXPECT_EQ(back.at<cv::Vec3w>(2, 2), cv::Vec3w(1000, 2000, 3000));
}

// What the report, the station and Deep Zoom tiles embed: the PNG OpenCV decodes to the same pixels.
TEST(HostImageIo, PngEncodedInMemoryDecodesToTheSamePixels) {
  for (const int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1, CV_16UC3, CV_16UC4}) {
    SCOPED_TRACE(type);
    const cv::Mat image = ramp(type, 13, 21);
    const std::string png = io::encode_png(image);
    const cv::Mat back =
        cv::imdecode(std::vector<std::uint8_t>(png.begin(), png.end()), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(back.type(), type);
    EXPECT_EQ(cv::norm(back, image, cv::NORM_INF), 0);
  }
  const cv::Mat whole = ramp(CV_8UC3, 20, 30);
  const cv::Mat part = whole(cv::Rect(3, 4, 11, 9));  // rows that are not contiguous
  const std::string png = io::encode_png(part);
  EXPECT_EQ(cv::norm(cv::imdecode(std::vector<std::uint8_t>(png.begin(), png.end()), cv::IMREAD_UNCHANGED),
                     part, cv::NORM_INF),
            0);
  EXPECT_THAT(error_of([&] { (void)io::encode_png(cv::Mat(3, 3, CV_32FC1, 0.5), "tile 3"); }),
              HasSubstr("tile 3: cannot write as PNG"));
  EXPECT_THAT(error_of([&] { (void)io::encode_png(cv::Mat(), "tile 4"); }), HasSubstr("tile 4"));
  // Wider than libpng writes (a million pixels): refused in the header, the encoder released (the
  // sanitizer build's leak check).
  EXPECT_THAT(error_of([&] { (void)io::encode_png(cv::Mat(1, 1'100'000, CV_8UC1, cv::Scalar(0)), "wide"); }),
              HasSubstr("wide: cannot write as PNG"));
}

}  // namespace
}  // namespace lightstage
