// io/exr.hpp: float EXR images written and read back through OpenEXR (1 and
// 3 channels, any channel order, NaN and infinities kept), the header read
// without decoding, and errors that name the file and the problem.
#include "lightstage/host/io/exr.hpp"
#include "lightstage/host/io/row_reader.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

namespace lightstage::io {
namespace {

using testing::error_of;

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Values no rounding could reproduce by accident, and the non-finite ones.
cv::Mat pattern(int rows, int cols, int channels) {
  cv::Mat image(rows, cols, CV_MAKETYPE(CV_32F, channels));
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      for (int k = 0; k < channels; ++k)
        image.ptr<float>(r)[c * channels + k] =
            std::ldexp(1.0f + 0.001f * static_cast<float>(r * 31 + c * 7 + k), (r + c + k) % 9 - 4) *
            (k % 2 ? -1.0f : 1.0f);
  image.ptr<float>(0)[0] = std::numeric_limits<float>::quiet_NaN();
  image.ptr<float>(1)[0] = std::numeric_limits<float>::infinity();
  return image;
}

// Bitwise equal, NaN included.
void expect_same(const cv::Mat& a, const cv::Mat& b) {
  ASSERT_EQ(a.type(), b.type());
  ASSERT_EQ(a.size(), b.size());
  for (int r = 0; r < a.rows; ++r)
    for (int i = 0; i < a.cols * a.channels(); ++i) {
      const float x = a.ptr<float>(r)[i], y = b.ptr<float>(r)[i];
      if (std::isnan(x)) {
        EXPECT_TRUE(std::isnan(y)) << r << " " << i;
      } else {
        EXPECT_EQ(x, y) << r << " " << i;
      }
    }
}

TEST(Exr, OneChannelRoundTripIsExact) {
  const auto path = testing::scratch_dir() / "depth.exr";
  const cv::Mat image = pattern(23, 37, 1);
  write_exr(path, image, {"Z"});
  const ExrFile file(path);
  EXPECT_EQ(file.header().size, cv::Size(37, 23));
  EXPECT_FALSE(file.header().cropped);
  EXPECT_FALSE(file.header().tiled);
  ASSERT_EQ(file.header().channels.size(), 1u);
  EXPECT_EQ(file.header().channels[0].name, "Z");
  EXPECT_EQ(file.header().channels[0].type, ExrPixelType::kFloat32);
  expect_same(file.read({"Z"}), image);
  expect_same(read_exr(path, {"Z"}), image);
  // Uncompressed: a block a row (its offset, y, size and every float) follows the header.
  EXPECT_GE(std::filesystem::file_size(path), 23u * (8 + 4 + 4 + 37 * sizeof(float)));
}

TEST(Exr, ThreeChannelsKeepTheCallersOrder) {
  const auto dir = testing::scratch_dir();
  const cv::Mat image = pattern(16, 9, 3);
  write_exr(dir / "rgb.exr", image, {"R", "G", "B"});
  expect_same(read_exr(dir / "rgb.exr", {"R", "G", "B"}), image);
  // Read back in another order, the channels follow their names.
  const cv::Mat bgr = read_exr(dir / "rgb.exr", {"B", "G", "R"});
  std::vector<cv::Mat> in, out;
  cv::split(image, in);
  cv::split(bgr, out);
  expect_same(out[0], in[2]);
  expect_same(out[1], in[1]);
  expect_same(out[2], in[0]);
  // One channel of three.
  expect_same(read_exr(dir / "rgb.exr", {"G"}), in[1]);
  // The file lists its channels sorted by name, all FLOAT.
  const ExrFile file(dir / "rgb.exr");
  ASSERT_EQ(file.header().channels.size(), 3u);
  EXPECT_EQ(file.header().channels[0].name, "B");
  EXPECT_EQ(file.header().channels[2].name, "R");
  for (const auto& channel : file.header().channels) EXPECT_EQ(channel.type, ExrPixelType::kFloat32);
}

TEST(Exr, NonContinuousImagesAndLongNamesAreWritten) {
  const auto dir = testing::scratch_dir();
  const cv::Mat big = pattern(20, 30, 3);
  const cv::Mat roi = big(cv::Rect(3, 4, 17, 11));
  ASSERT_FALSE(roi.isContinuous());
  write_exr(dir / "roi.exr", roi, {"normal.X", "normal.Y", "normal.Z"});
  expect_same(read_exr(dir / "roi.exr", {"normal.X", "normal.Y", "normal.Z"}), roi.clone());
  const std::string long_name(64, 'n');  // past the 31 bytes of OpenEXR's short names
  write_exr(dir / "long.exr", pattern(4, 5, 1), {long_name});
  expect_same(read_exr(dir / "long.exr", {long_name}), pattern(4, 5, 1));
}

TEST(Exr, WritingIsAtomicAndReplacesTheFile) {
  const auto dir = testing::scratch_dir();
  write_exr(dir / "a.exr", pattern(5, 5, 1), {"Y"});
  write_exr(dir / "a.exr", pattern(6, 7, 1), {"Y"});
  EXPECT_EQ(ExrFile(dir / "a.exr").header().size, cv::Size(7, 6));
  // Nothing but the file is left in the folder.
  int entries = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 1);
}

TEST(Exr, WriteErrorsNameTheFile) {
  const auto dir = testing::scratch_dir();
  const auto path = dir / "w.exr";
  EXPECT_NE(error_of([&] {
              write_exr(path, cv::Mat(4, 4, CV_8UC1, cv::Scalar(1)), {"Y"});
            }).find("w.exr: cannot write as EXR: expected CV_32FC1 or CV_32FC3"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              write_exr(path, cv::Mat(4, 4, CV_32FC2, cv::Scalar(1)), {"X", "Y"});
            }).find("w.exr: cannot write as EXR: expected CV_32FC1 or CV_32FC3"),
            std::string::npos);
  EXPECT_NE(error_of([&] { write_exr(path, cv::Mat(), {"Y"}); }).find("w.exr: cannot write as EXR"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              write_exr(path, pattern(4, 4, 3), {"R", "G"});
            }).find("w.exr: cannot write as EXR: 2 channel name(s) for 3 channel(s)"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              write_exr(path, pattern(4, 4, 3), {"R", "G", "R"});
            }).find("w.exr: cannot write as EXR: channel name 'R' repeated"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              write_exr(path, pattern(4, 4, 1), {""});
            }).find("w.exr: cannot write as EXR: channel name ''"),
            std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_NE(error_of([&] {
              write_exr(dir / "no-such-dir" / "x.exr", pattern(4, 4, 1), {"Y"});
            }).find("x.exr: cannot write"),
            std::string::npos);
}

TEST(Exr, ReadErrorsNameTheFileAndTheProblem) {
  const auto dir = testing::scratch_dir();
  write_exr(dir / "rgb.exr", pattern(10, 12, 3), {"R", "G", "B"});
  EXPECT_NE(error_of([&] {
              read_exr(dir / "rgb.exr", {"Z"});
            }).find("rgb.exr: EXR has no channel 'Z' (it has 'B', 'G', 'R')"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              read_exr(dir / "rgb.exr", {"R", "R"});
            }).find("rgb.exr: EXR channel 'R' asked for twice"),
            std::string::npos);
  EXPECT_NE(error_of([&] { read_exr(dir / "rgb.exr", {}); }).find("rgb.exr: cannot read 0 EXR channels"),
            std::string::npos);
  EXPECT_NE(error_of([&] { read_exr(dir / "missing.exr", {"Y"}); }).find("missing.exr: cannot open"),
            std::string::npos);
  write_bytes(dir / "text.exr", "not an exr\n");
  EXPECT_NE(error_of([&] { read_exr(dir / "text.exr", {"Y"}); }).find("text.exr: not an OpenEXR file"),
            std::string::npos);
  write_bytes(dir / "empty.exr", "");
  EXPECT_NE(error_of([&] { read_exr(dir / "empty.exr", {"Y"}); }).find("empty.exr: not an OpenEXR file"),
            std::string::npos);

  const std::string bytes = read_bytes(dir / "rgb.exr");
  // The version field: 3 is not a version, bit 12 is a multi-part file.
  std::string edited = bytes;
  edited[4] = 3;
  EXPECT_NE(
      error_of([&] { ExrFile(edited, "v3.exr"); }).find("v3.exr: EXR version 3 is not supported (2 is)"),
      std::string::npos);
  edited = bytes;
  edited[5] = static_cast<char>(edited[5] | 0x10);
  EXPECT_NE(error_of([&] {
              ExrFile(edited, "multi.exr");
            }).find("multi.exr: deep or multi-part EXR files are not read"),
            std::string::npos);
  // Cut inside the header, then inside the pixels.
  EXPECT_NE(error_of([&] {
              ExrFile(bytes.substr(0, 40), "cut.exr");
            }).find("cut.exr: EXR header ends inside the file (truncated file)"),
            std::string::npos);
  const ExrFile cut(bytes.substr(0, bytes.size() - 64), "cut-pixels.exr");
  EXPECT_NE(error_of([&] {
              cut.read({"R", "G", "B"});
            }).find("cut-pixels.exr: cannot decode EXR channels 'R', 'G', 'B': "),
            std::string::npos);
}

// Files other writers make (the fuzz corpus: a selector byte, then the file,
// written with OpenEXR): tiled, HALF and UINT, cropped, subsampled.
ExrFile corpus_file(const std::string& name) {
  const std::string bytes = read_bytes(testing::source_dir() / "tests/fuzz/corpus/exr" / name);
  return ExrFile(bytes.substr(1), name);
}

TEST(Exr, TiledHalfUintCroppedAndSubsampledFiles) {
  const ExrFile tiled = corpus_file("rgb-tiled-piz.exr.bin");
  EXPECT_TRUE(tiled.header().tiled);
  const cv::Mat rgb = tiled.read({"R", "G", "B"});
  ASSERT_EQ(rgb.size(), cv::Size(8, 6));
  // Written as sin(0.1 i) * 5 over the interleaved R, G, B values.
  for (int r = 0; r < rgb.rows; ++r)
    for (int i = 0; i < rgb.cols * 3; ++i)
      EXPECT_EQ(rgb.ptr<float>(r)[i], std::sin(0.1f * static_cast<float>(r * rgb.cols * 3 + i)) * 5)
          << r << " " << i;

  const ExrFile mixed = corpus_file("z-half-a-uint-cropped-rle.exr.bin");
  ASSERT_EQ(mixed.header().channels.size(), 2u);
  EXPECT_EQ(mixed.header().channels[0].type, ExrPixelType::kUint32);
  EXPECT_EQ(mixed.header().channels[1].type, ExrPixelType::kHalf);
  EXPECT_TRUE(mixed.header().cropped);
  EXPECT_EQ(mixed.header().size, cv::Size(8, 6));
  EXPECT_NE(error_of([&] {
              mixed.read({"Z"});
            }).find("z-half-a-uint-cropped-rle.exr.bin: EXR data window differs from the display window"),
            std::string::npos);

  const ExrFile sub = corpus_file("y-float-subsampled.exr.bin");
  EXPECT_NE(error_of([&] {
              sub.read({"RY"});
            }).find("y-float-subsampled.exr.bin: EXR channel 'RY' is subsampled (2x2)"),
            std::string::npos);
  EXPECT_EQ(sub.read({"Y"}).size(), cv::Size(8, 6));
}

TEST(Exr, RowBandsEqualTheWholeReadForScanLinesAndTiles) {
  const auto dir = testing::scratch_dir();
  const cv::Mat image = pattern(37, 11, 3);
  write_exr(dir / "rgb.exr", image, {"B", "G", "R"});
  write_bytes(dir / "tiled.exr",
              read_bytes(testing::source_dir() / "tests/fuzz/corpus/exr/rgb-tiled-piz.exr.bin").substr(1));
  for (const auto& [file, whole] :
       {std::pair{dir / "rgb.exr", image},
        std::pair{dir / "tiled.exr", read_exr(dir / "tiled.exr", {"B", "G", "R"})}}) {
    const auto rows = open_exr_rows(file, {"B", "G", "R"});
    ASSERT_EQ(rows->size(), whole.size());
    cv::Mat band;
    for (const int height : {1, 4, 16}) {
      // Top to bottom, then a band above the last one read.
      for (int y = 0; y < whole.rows; y += height) {
        const int n = std::min(height, whole.rows - y);
        rows->read(y, n, band);
        expect_same(band, whole.rowRange(y, y + n));
      }
      rows->read(1, 2, band);
      expect_same(band, whole.rowRange(1, 3));
    }
  }
  EXPECT_NE(error_of([&] { open_exr_rows(dir / "rgb.exr", {"Y"}); }).find("rgb.exr: EXR has no channel 'Y'"),
            std::string::npos);
  EXPECT_NE(error_of([&] { open_exr_rows(dir / "none.exr", {"Y"}); }).find("none.exr: no such file"),
            std::string::npos);
  // Cut short: found as the reader is opened or as its rows are decoded, naming the file.
  const std::string bytes = read_bytes(dir / "rgb.exr");
  write_bytes(dir / "short.exr", bytes.substr(0, bytes.size() * 2 / 3));
  EXPECT_NE(error_of([&] {
              cv::Mat rows_read;
              open_exr_rows(dir / "short.exr", {"R"})->read(0, 37, rows_read);
            }).find("short.exr"),
            std::string::npos);
}

TEST(Exr, HugeDimensionsAreRefusedFromTheHeader) {
  // A header asking for 70000 x 1 pixels: the data and display windows are
  // rewritten in place (box2i: xMin yMin xMax yMax, little-endian int32).
  const auto dir = testing::scratch_dir();
  write_exr(dir / "small.exr", pattern(1, 2, 1), {"Y"});
  std::string bytes = read_bytes(dir / "small.exr");
  for (const std::string& key :
       {std::string("dataWindow\0box2i\0", 17), std::string("displayWindow\0box2i\0", 20)}) {
    const auto at = bytes.find(key);
    ASSERT_NE(at, std::string::npos);
    const std::size_t x_max = at + key.size() + 4 + 8;
    const std::int32_t wide = 69999;
    for (int i = 0; i < 4; ++i)
      bytes[x_max + static_cast<std::size_t>(i)] = static_cast<char>((wide >> (8 * i)) & 0xff);
  }
  EXPECT_NE(error_of([&] { ExrFile(bytes, "wide.exr"); }).find("wide.exr: EXR image is 70000x1; at most"),
            std::string::npos);
}

}  // namespace
}  // namespace lightstage::io
