// Images written a band at a time (row_writer.hpp) read back as the images
// written whole, in every format and type a solve writes; nothing appears at
// the file's name before the last row, and a failing disk leaves nothing.
#include "lightstage/host/io/row_writer.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/exr.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/write_fault.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cerrno>
#include <filesystem>
#include <string>
#include <vector>

namespace lightstage {
namespace {

namespace fs = std::filesystem;
using testing::device_error_of;
using testing::error_of;
using ::testing::HasSubstr;

const cv::Size kSize(29, 19);  // no band height divides it

cv::Mat random_image(int type) {
  cv::Mat image(kSize, type);
  const double high = CV_MAT_DEPTH(type) == CV_8U ? 256 : CV_MAT_DEPTH(type) == CV_16U ? 65536 : 10;
  cv::randu(image, cv::Scalar::all(CV_MAT_DEPTH(type) == CV_32F ? -high : 0), cv::Scalar::all(high));
  return image;
}

// Writes `image` through `writer` in bands of `band` rows.
void write_in_bands(io::RowWriter& writer, const cv::Mat& image, int band) {
  for (int y = 0; y < image.rows; y += band) {
    writer.write(image.rowRange(y, std::min(image.rows, y + band)));
    EXPECT_FALSE(fs::exists(writer.path())) << "a partial image is visible";
  }
  writer.commit();
}

void expect_same(const cv::Mat& actual, const cv::Mat& expected, const std::string& what) {
  ASSERT_EQ(actual.type(), expected.type()) << what;
  ASSERT_EQ(actual.size(), expected.size()) << what;
  EXPECT_EQ(cv::norm(actual, expected, cv::NORM_INF), 0) << what;
}

std::vector<std::string> files_in(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  return names;
}

TEST(RowWriter, BandsReadBackAsTheWholeImageInEveryFormat) {
  const fs::path dir = lightstage::testing::scratch_dir();
  for (const int band : {1, 4, 19}) {
    SCOPED_TRACE(band);
    for (const int type : {CV_8UC1, CV_8UC3, CV_16UC1, CV_16UC3}) {
      const cv::Mat image = random_image(type);
      const fs::path file = dir / "image.png";
      write_in_bands(*io::open_png_writer(file, kSize, type), image, band);
      expect_same(io::read_image(file), image, cv::typeToString(type) + " png");
      fs::remove(file);
    }
    for (const int type : {CV_32FC1, CV_32FC3}) {
      const cv::Mat image = random_image(type);
      write_in_bands(*io::open_pfm_writer(dir / "image.pfm", kSize, type), image, band);
      expect_same(io::read_pfm(dir / "image.pfm"), image, cv::typeToString(type) + " pfm");
      const std::vector<std::string> channels =
          type == CV_32FC1 ? std::vector<std::string>{"Y"} : std::vector<std::string>{"B", "G", "R"};
      write_in_bands(*io::open_exr_writer(dir / "image.exr", kSize, type, channels), image, band);
      expect_same(io::read_exr(dir / "image.exr", channels), image, cv::typeToString(type) + " exr");
      fs::remove(dir / "image.pfm");
      fs::remove(dir / "image.exr");
    }
  }
  EXPECT_TRUE(files_in(dir).empty()) << "temporary files left behind";
}

TEST(RowWriter, WrongRowsAndUnfinishedImagesAreRefusedAndLeaveNothing) {
  const fs::path dir = lightstage::testing::scratch_dir();
  {
    const auto writer = io::open_pfm_writer(dir / "a.pfm", kSize, CV_32FC1);
    EXPECT_THAT(error_of([&] { writer->write(random_image(CV_32FC3)); }),
                HasSubstr("a.pfm: rows of CV_32FC3"));
    EXPECT_THAT(error_of([&] { writer->write(cv::Mat(2, kSize.width + 1, CV_32FC1)); }),
                HasSubstr("width 30 given"));
    writer->write(random_image(CV_32FC1).rowRange(0, 10));
    EXPECT_THAT(error_of([&] { writer->write(random_image(CV_32FC1)); }),
                HasSubstr("19 more rows given after 10"));
    EXPECT_THAT(error_of([&] { writer->commit(); }), HasSubstr("10 of 19 rows written"));
  }
  {
    const auto writer = io::open_png_writer(dir / "b.png", kSize, CV_16UC3);
    writer->write(random_image(CV_16UC3).rowRange(0, 3));
  }  // abandoned: its temporary file goes with it
  EXPECT_TRUE(files_in(dir).empty());
  EXPECT_THAT(error_of([&] { io::open_png_writer(dir / "c.png", kSize, CV_32FC1); }),
              HasSubstr("c.png: cannot write as PNG"));
  EXPECT_THAT(error_of([&] {
                io::open_exr_writer(dir / "c.exr", kSize, CV_32FC3, {"R", "G"});
              }),
              HasSubstr("2 channel name(s) for 3"));
}

TEST(RowWriter, AFullDiskIsAnErrorNamingTheFileAndLeavesNothing) {
  const fs::path dir = lightstage::testing::scratch_dir();
  const io::ScopedWriteFault full([](const fs::path&) { return ENOSPC; });
  for (const char* name : {"n.png", "n.pfm", "n.exr"}) {
    const std::string message = device_error_of([&] {
      const fs::path file = dir / name;
      const std::string extension = file.extension().string();
      const auto writer = extension == ".png"   ? io::open_png_writer(file, kSize, CV_16UC3)
                          : extension == ".pfm" ? io::open_pfm_writer(file, kSize, CV_32FC3)
                                                : io::open_exr_writer(file, kSize, CV_32FC3, {"B", "G", "R"});
      write_in_bands(*writer, random_image(writer->type()), 4);
    });
    EXPECT_THAT(message, HasSubstr(name));
    EXPECT_THAT(message, HasSubstr("no space left on the device"));
    EXPECT_THAT(message, ::testing::Not(HasSubstr("InputError")));
  }
  EXPECT_TRUE(files_in(dir).empty());
}

}  // namespace
}  // namespace lightstage
