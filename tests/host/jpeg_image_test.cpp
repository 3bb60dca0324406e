#include "lightstage/host/io/jpeg_image.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/exif.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <exiv2/exiv2.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

namespace lightstage {
namespace {

using testing::error_of;
using ::testing::HasSubstr;

// Smooth, so that JPEG's error is small and measures the quality asked for.
cv::Mat gradient(int type, int rows = 48, int cols = 64) {
  cv::Mat image(rows, cols, type);
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x)
      for (int c = 0; c < image.channels(); ++c)
        image.ptr<std::uint8_t>(y)[x * image.channels() + c] =
            static_cast<std::uint8_t>(20 + x + y + 30 * c + 10 * std::sin(0.3 * x * (c + 1)));
  return image;
}

void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

std::string opencv_jpeg(const cv::Mat& image, const std::vector<int>& params) {
  std::vector<std::uint8_t> bytes;
  EXPECT_TRUE(cv::imencode(".jpg", image, bytes, params));
  return {bytes.begin(), bytes.end()};
}

void expect_same(const cv::Mat& a, const cv::Mat& b) {
  ASSERT_EQ(a.type(), b.type());
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0);
}

TEST(HostJpegImage, DecodesPixelForPixelAsOpenCvDid) {
  const auto dir = testing::scratch_dir();
  const struct {
    const char* name;
    int type;
    std::vector<int> params;
  } cases[] = {
      {"colour", CV_8UC3, {cv::IMWRITE_JPEG_QUALITY, 90}},
      {"colour-progressive", CV_8UC3, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}},
      {"colour-optimised-restarts",
       CV_8UC3,
       {cv::IMWRITE_JPEG_OPTIMIZE, 1, cv::IMWRITE_JPEG_RST_INTERVAL, 2}},
      {"grey", CV_8UC1, {cv::IMWRITE_JPEG_QUALITY, 75}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    cv::Mat noisy = gradient(c.type, 37, 53);  // sides that are no multiple of the 8 or 16 pixel blocks
    cv::Mat noise(noisy.size(), c.type);
    cv::randu(noise, 0, 30);
    noisy += noise;
    const auto path = dir / (std::string(c.name) + ".jpg");
    write_bytes(path, opencv_jpeg(noisy, c.params));
    const cv::Mat ours = io::read_jpeg(path);
    expect_same(ours, cv::imread(path.string(), cv::IMREAD_UNCHANGED));
    expect_same(io::read_image(path), ours);
    EXPECT_EQ(io::read_jpeg_size(path), noisy.size());
  }
}

TEST(HostJpegImage, EncodesAtTheQualityAsked) {
  for (const int type : {CV_8UC3, CV_8UC1}) {
    SCOPED_TRACE(type);
    const cv::Mat image = gradient(type);
    const std::string fine = io::encode_jpeg(image, 95), coarse = io::encode_jpeg(image, 30);
    const std::vector<std::uint8_t> fine_bytes(fine.begin(), fine.end());
    const cv::Mat decoded = cv::imdecode(fine_bytes, cv::IMREAD_UNCHANGED);
    expect_same(io::decode_jpeg(fine_bytes, "fine"), decoded);
    const cv::Mat coarse_decoded =
        cv::imdecode(std::vector<std::uint8_t>(coarse.begin(), coarse.end()), cv::IMREAD_UNCHANGED);
    EXPECT_GT(cv::PSNR(decoded, image), 40.0);
    EXPECT_LT(cv::PSNR(coarse_decoded, image), cv::PSNR(decoded, image));
    EXPECT_LT(coarse.size(), fine.size());
  }
  // Blue, green and red stay themselves (BGR in memory, RGB in the file).
  const cv::Mat blue(16, 16, CV_8UC3, cv::Scalar(255, 0, 0)), red(16, 16, CV_8UC3, cv::Scalar(0, 0, 255));
  const std::string blue_jpeg = io::encode_jpeg(blue, 95), red_jpeg = io::encode_jpeg(red, 95);
  EXPECT_LT(
      cv::norm(cv::imdecode(std::vector<std::uint8_t>(blue_jpeg.begin(), blue_jpeg.end()), cv::IMREAD_COLOR),
               blue, cv::NORM_INF),
      8);
  EXPECT_LT(
      cv::norm(cv::imdecode(std::vector<std::uint8_t>(red_jpeg.begin(), red_jpeg.end()), cv::IMREAD_COLOR),
               red, cv::NORM_INF),
      8);
}

TEST(HostJpegImage, WritesAtomically) {
  const auto dir = testing::scratch_dir();
  io::write_jpeg(dir / "a.jpg", gradient(CV_8UC3), 90);
  io::write_jpeg(dir / "a.jpg", gradient(CV_8UC1), 90);  // over the first
  EXPECT_EQ(io::read_jpeg(dir / "a.jpg").type(), CV_8UC1);
  int files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 1);
}

TEST(HostJpegImage, IsKnownByItsContentNotItsName) {
  const auto dir = testing::scratch_dir();
  const cv::Mat image = gradient(CV_8UC3);
  io::write_jpeg(dir / "photo.png", image, 90);
  io::write_png(dir / "photo.jpg", image);
  EXPECT_TRUE(io::is_jpeg_file(dir / "photo.png"));
  EXPECT_FALSE(io::is_jpeg_file(dir / "photo.jpg"));
  EXPECT_FALSE(io::is_jpeg_file(dir / "absent.jpg"));
  EXPECT_GT(cv::PSNR(io::read_image(dir / "photo.png"), image), 40.0);
  expect_same(io::read_image(dir / "photo.jpg"), image);
}

TEST(HostJpegImage, BrokenFilesAndImagesItCannotWriteAreRefusedNamingThem) {
  const auto dir = testing::scratch_dir();
  cv::Mat noise(64, 64, CV_8UC3);
  cv::randu(noise, 0, 256);
  const std::string whole = io::encode_jpeg(noise, 90);  // mostly image data, little header
  write_bytes(dir / "cut.jpg", whole.substr(0, whole.size() / 2));
  EXPECT_THAT(error_of([&] { io::read_jpeg(dir / "cut.jpg"); }), HasSubstr("cut.jpg: cannot decode"));
  EXPECT_THAT(error_of([&] { io::read_image(dir / "cut.jpg"); }), HasSubstr("cut.jpg: cannot decode"));
  write_bytes(dir / "head.jpg", whole.substr(0, 40));
  EXPECT_THAT(error_of([&] { io::read_jpeg(dir / "head.jpg"); }), HasSubstr("head.jpg: not a readable JPEG"));
  write_bytes(dir / "text.jpg", "not a JPEG at all\n");
  EXPECT_THAT(error_of([&] { io::read_jpeg(dir / "text.jpg"); }), HasSubstr("text.jpg: not a readable JPEG"));
  EXPECT_THAT(error_of([&] { io::read_image(dir / "text.jpg"); }),
              HasSubstr("text.jpg: not a readable image (PNG, JPEG, TIFF, PFM or camera RAW expected)"));
  EXPECT_THAT(error_of([&] { io::read_jpeg(dir / "absent.jpg"); }), HasSubstr("absent.jpg: cannot open"));

  EXPECT_THAT(error_of([&] { io::write_jpeg(dir / "deep.jpg", cv::Mat(4, 4, CV_16UC1, 7), 90); }),
              HasSubstr("deep.jpg: cannot write as JPEG"));
  EXPECT_THAT(error_of([&] { io::write_jpeg(dir / "zero.jpg", gradient(CV_8UC1), 0); }),
              HasSubstr("zero.jpg: JPEG quality 0 (1 to 100)"));
  EXPECT_THAT(error_of([&] { io::write_jpeg(dir / "no" / "folder.jpg", gradient(CV_8UC1), 90); }),
              HasSubstr("folder.jpg"));
  // A header declaring more than a stack may hold (16384 a side) is refused before any pixel is decoded.
  std::string huge = io::encode_jpeg(gradient(CV_8UC1), 90);
  const std::size_t frame =
      huge.find("\xFF\xC0");  // baseline start of frame: length, precision, height, width
  ASSERT_NE(frame, std::string::npos);
  huge[frame + 5] = huge[frame + 7] = '\x4E';  // 0x4E20 = 20000
  huge[frame + 6] = huge[frame + 8] = '\x20';
  write_bytes(dir / "huge.jpg", huge);
  EXPECT_THAT(error_of([&] { io::read_jpeg(dir / "huge.jpg"); }),
              HasSubstr("huge.jpg: JPEG of 20000x20000 pixels, larger than the 16384 a side this reads"));
  EXPECT_THAT(error_of([&] { io::read_jpeg_size(dir / "huge.jpg"); }), HasSubstr("huge.jpg"));
  EXPECT_FALSE(std::filesystem::exists(dir / "deep.jpg"));
  EXPECT_FALSE(std::filesystem::exists(dir / "zero.jpg"));
}

// What a viewer shows, by the EXIF 2.3 definition of each Orientation value:
// which side of the picture the stored row 0 and column 0 are.
cv::Mat shown(const cv::Mat& stored, int orientation) {
  const int h = stored.rows, w = stored.cols;
  const bool turned = orientation >= 5;
  cv::Mat out(turned ? w : h, turned ? h : w, stored.type());
  for (int i = 0; i < out.rows; ++i)
    for (int j = 0; j < out.cols; ++j) {
      int y = i, x = j;  // 1: row 0 at the top, column 0 on the left
      switch (orientation) {
        case 2:
          x = w - 1 - j;
          break;  // column 0 on the right
        case 3:
          y = h - 1 - i, x = w - 1 - j;
          break;  // row 0 at the bottom, column 0 on the right
        case 4:
          y = h - 1 - i;
          break;  // row 0 at the bottom
        case 5:
          y = j, x = i;
          break;  // row 0 on the left, column 0 at the top
        case 6:
          y = h - 1 - j, x = i;
          break;  // row 0 on the right, column 0 at the top
        case 7:
          y = h - 1 - j, x = w - 1 - i;
          break;  // row 0 on the right, column 0 at the bottom
        case 8:
          y = j, x = w - 1 - i;
          break;  // row 0 on the left, column 0 at the bottom
        default:
          break;
      }
      out.at<std::uint8_t>(i, j) = stored.at<std::uint8_t>(y, x);
    }
  return out;
}

TEST(HostJpegImage, ExifOrientationTurnsAPhotoUpright) {
  cv::Mat stored(3, 5, CV_8UC1);
  for (int i = 0; i < stored.rows * stored.cols; ++i)
    stored.at<std::uint8_t>(i / 5, i % 5) = static_cast<std::uint8_t>(i);
  for (int orientation = 1; orientation <= 8; ++orientation) {
    SCOPED_TRACE(orientation);
    expect_same(io::turn_upright(stored, orientation), shown(stored, orientation));
  }
  cv::Mat clockwise;
  cv::rotate(stored, clockwise, cv::ROTATE_90_CLOCKWISE);  // a camera held turned anticlockwise: 6
  expect_same(io::turn_upright(stored, 6), clockwise);
  expect_same(io::turn_upright(stored, 0), stored);
  expect_same(io::turn_upright(stored, 9), stored);
}

TEST(HostJpegImage, OrientationIsReadFromTheExif) {
  const auto dir = testing::scratch_dir();
  const auto tagged = [&](const std::string& name, std::uint16_t value) {
    const auto path = dir / name;
    io::write_jpeg(path, gradient(CV_8UC3), 90);
    auto image = Exiv2::ImageFactory::open(path.string());
    image->readMetadata();
    Exiv2::ExifData& exif = image->exifData();
    exif["Exif.Image.Orientation"] = value;
    image->writeMetadata();
    return path;
  };
  EXPECT_EQ(io::read_exif(tagged("six.jpg", 6)).orientation, 6);
  EXPECT_EQ(io::read_exif(tagged("one.jpg", 1)).orientation, 1);
  EXPECT_EQ(io::read_exif(tagged("nine.jpg", 9)).orientation, std::nullopt);
  io::write_jpeg(dir / "plain.jpg", gradient(CV_8UC1), 90);
  EXPECT_EQ(io::read_exif(dir / "plain.jpg").orientation, std::nullopt);
  EXPECT_FALSE(io::read_exif(tagged("six.jpg", 6)).to_json().contains("orientation"));
}

}  // namespace
}  // namespace lightstage
