#include "lightstage/host/io/row_reader.hpp"
#include "lightstage/host/io/temporary_rows.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"
#include "tiff_writer.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <png.h>
#include <tiffio.h>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <bit>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

namespace lightstage {
namespace {

using testing::error_of;
using ::testing::HasSubstr;
using testing::write_tiff;
using testing::Written;

// Odd sides: no band height, strip or tile divides them.
constexpr int kWidth = 37;
constexpr int kHeight = 23;

// An image of `type` with every sample drawn from [0, high).
cv::Mat random_image(int type, double high, cv::Size size = {kWidth, kHeight}) {
  cv::Mat image(size, type);
  cv::randu(image, cv::Scalar::all(0), cv::Scalar::all(high));
  return image;
}

cv::Mat merged(const std::vector<cv::Mat>& planes) {
  cv::Mat out;
  cv::merge(planes, out);
  return out;
}

// Channels in the other order: file RGB to BGR in memory (a grey image as it is).
cv::Mat reversed(const cv::Mat& image) {
  std::vector<cv::Mat> planes;
  cv::split(image, planes);
  std::reverse(planes.begin(), planes.end());
  return merged(planes);
}

void expect_same(const cv::Mat& actual, const cv::Mat& expected) {
  ASSERT_EQ(actual.type(), expected.type());
  ASSERT_EQ(actual.size(), expected.size());
  EXPECT_EQ(cv::norm(actual, expected, cv::NORM_INF), 0);
}

// Reads rows [y0, y0 + rows) and compares them with the same rows of `whole`.
void expect_band(io::RowReader& reader, const cv::Mat& whole, int y0, int rows) {
  SCOPED_TRACE("rows " + std::to_string(y0) + " to " + std::to_string(y0 + rows - 1));
  cv::Mat band;
  reader.read(y0, rows, band);
  expect_same(band, whole.rowRange(y0, y0 + rows));
}

// Reads `path` band by band, comparing every band with the rows of `whole`
// (read_image's): top to bottom in bands of several heights, each sweep
// followed by a band above the last one read; bottom to top; and a range
// further down read first, then the rows above it, then the rest.
void expect_bands_match(const std::filesystem::path& path, const cv::Mat& whole, bool decoded_whole = false) {
  SCOPED_TRACE(path.filename().string());
  const int height = whole.rows;
  for (const int band : {1, 5, 7, height}) {
    SCOPED_TRACE("bands of " + std::to_string(band) + " rows");
    const auto reader = io::open_row_reader(path);
    ASSERT_EQ(reader->size(), whole.size());
    ASSERT_EQ(reader->type(), whole.type());
    EXPECT_EQ(reader->decoded_whole(), decoded_whole);
    for (int y0 = 0; y0 < height; y0 += band) expect_band(*reader, whole, y0, std::min(band, height - y0));
    expect_band(*reader, whole, height / 3, std::min(3, height - height / 3));
  }
  {
    SCOPED_TRACE("bottom to top");
    const auto reader = io::open_row_reader(path);
    for (int end = height; end > 0; end -= 4) {
      const int y0 = std::max(0, end - 4);
      expect_band(*reader, whole, y0, end - y0);
    }
  }
  SCOPED_TRACE("a range further down first");
  const int skip = std::min(10, height / 2);
  const int skipped = std::min(5, height - skip);
  const auto reader = io::open_row_reader(path);
  expect_band(*reader, whole, skip, skipped);
  if (skip > 0) expect_band(*reader, whole, 0, skip);
  if (skip + skipped < height) expect_band(*reader, whole, skip + skipped, height - skip - skipped);
}

TEST(HostRowReader, PngBandsEqualReadImageForEveryDepthAndChannelCount) {
  const auto dir = testing::scratch_dir();
  const struct {
    const char* name;
    int type;  // as written; read without the alpha channel
  } cases[] = {
      {"grey8", CV_8UC1},  {"grey16", CV_16UC1}, {"bgr8", CV_8UC3},
      {"bgr16", CV_16UC3}, {"bgra8", CV_8UC4},   {"bgra16", CV_16UC4},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const cv::Mat written = random_image(c.type, CV_MAT_DEPTH(c.type) == CV_8U ? 256 : 65536);
    const auto path = dir / (std::string(c.name) + ".png");
    ASSERT_TRUE(cv::imwrite(path.string(), written));
    cv::Mat expected = written;
    if (written.channels() == 4) {
      std::vector<cv::Mat> planes;
      cv::split(written, planes);
      planes.pop_back();
      expected = merged(planes);
    }
    const cv::Mat whole = io::read_image(path);
    expect_same(whole, expected);
    expect_bands_match(path, whole);
  }
}

// How a PNG written through libpng (below) is laid out.
struct PngSpec {
  int colour = PNG_COLOR_TYPE_GRAY;
  int bit_depth = 8;
  int interlace = PNG_INTERLACE_NONE;
  std::vector<png_color> palette = {};
  std::vector<png_byte> palette_alpha = {};  // a tRNS chunk when not empty
};

struct PngJob {
  std::FILE* file = nullptr;
  png_uint_32 width = 0, height = 0;
  const PngSpec* spec = nullptr;
  png_bytepp rows = nullptr;
};

// libpng reports errors by longjmp: this function holds no C++ object with a
// destructor and changes no local after its setjmp.
bool encode_png(png_structp png, png_infop info, const PngJob* job) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_init_io(png, job->file);
  png_set_IHDR(png, info, job->width, job->height, job->spec->bit_depth, job->spec->colour,
               job->spec->interlace, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (!job->spec->palette.empty())
    png_set_PLTE(png, info, job->spec->palette.data(), static_cast<int>(job->spec->palette.size()));
  if (!job->spec->palette_alpha.empty())
    png_set_tRNS(png, info, job->spec->palette_alpha.data(),
                 static_cast<int>(job->spec->palette_alpha.size()), nullptr);
  png_write_info(png, info);
  png_write_image(png, job->rows);  // all seven passes of an interlaced image
  png_write_end(png, nullptr);
  return true;
}

// Writes `data`, `height` rows of samples packed as the PNG stores them (see png_bytes).
void write_png_file(const std::filesystem::path& path, int width, int height, const PngSpec& spec,
                    std::vector<png_byte> data) {
  const std::size_t row_bytes = data.size() / static_cast<std::size_t>(height);
  std::vector<png_bytep> rows(static_cast<std::size_t>(height));
  for (std::size_t y = 0; y < rows.size(); ++y) rows[y] = data.data() + y * row_bytes;
  std::FILE* file = std::fopen(path.c_str(), "wb");
  ASSERT_NE(file, nullptr) << path;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
  const PngJob job{file, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), &spec,
                   rows.data()};
  const bool written = info != nullptr && encode_png(png, info, &job);
  png_destroy_write_struct(&png, &info);
  const bool closed = std::fclose(file) == 0;
  ASSERT_TRUE(written) << path;
  ASSERT_TRUE(closed) << path;
}

// The samples of `image` as a PNG stores them: `bits` (1, 2, 4 or 8) bits
// each, packed from the high bit, or 16 bits big-endian; rows start on a byte.
std::vector<png_byte> png_bytes(const cv::Mat& image, int bits) {
  const cv::Mat samples = image.reshape(1);
  const std::size_t row_bytes =
      (static_cast<std::size_t>(samples.cols) * static_cast<std::size_t>(bits) + 7) / 8;
  std::vector<png_byte> data(row_bytes * static_cast<std::size_t>(samples.rows), 0);
  for (int y = 0; y < samples.rows; ++y) {
    png_byte* row = data.data() + static_cast<std::size_t>(y) * row_bytes;
    for (int x = 0; x < samples.cols; ++x) {
      const int bit = x * bits;
      if (bits == 16) {
        const std::uint16_t value = samples.at<std::uint16_t>(y, x);
        row[bit / 8] = static_cast<png_byte>(value >> 8);
        row[bit / 8 + 1] = static_cast<png_byte>(value & 0xff);
      } else {
        row[bit / 8] |= static_cast<png_byte>(samples.at<std::uint8_t>(y, x) << (8 - bits - bit % 8));
      }
    }
  }
  return data;
}

// The BGR image of palette indexes.
cv::Mat from_palette(const cv::Mat& indexes, const std::vector<png_color>& palette) {
  cv::Mat bgr(indexes.size(), CV_8UC3);
  for (int y = 0; y < indexes.rows; ++y)
    for (int x = 0; x < indexes.cols; ++x) {
      const png_color& colour = palette[indexes.at<std::uint8_t>(y, x)];
      bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(colour.blue, colour.green, colour.red);
    }
  return bgr;
}

TEST(HostRowReader, PngColourTypesAreTransformedAsReadImageTransformsThem) {
  const auto dir = testing::scratch_dir();
  std::vector<png_color> palette;
  for (int i = 0; i < 7; ++i)
    palette.push_back({static_cast<png_byte>(37 * i + 3), static_cast<png_byte>(250 - 31 * i),
                       static_cast<png_byte>(5 * i * i)});
  const std::vector<png_byte> alpha = {0, 64, 128, 255, 17};  // the first five entries; the others opaque
  const cv::Mat indexes = random_image(CV_8UC1, 7);
  const cv::Mat one_bit = random_image(CV_8UC1, 2);
  const cv::Mat four_bit = random_image(CV_8UC1, 16);
  const cv::Mat grey8 = random_image(CV_8UC1, 256), alpha8 = random_image(CV_8UC1, 256);
  const cv::Mat grey16 = random_image(CV_16UC1, 65536), alpha16 = random_image(CV_16UC1, 65536);
  const cv::Mat rgb = random_image(CV_8UC3, 256);  // in file order
  const struct {
    std::string name;
    PngSpec spec;
    std::vector<png_byte> data;
    cv::Mat expected;  // what read_image gives
  } cases[] = {
      {"palette8",
       {.colour = PNG_COLOR_TYPE_PALETTE, .palette = palette},
       png_bytes(indexes, 8),
       from_palette(indexes, palette)},
      {"palette8-trns",
       {.colour = PNG_COLOR_TYPE_PALETTE, .palette = palette, .palette_alpha = alpha},
       png_bytes(indexes, 8),
       from_palette(indexes, palette)},
      {"palette4-trns",
       {.colour = PNG_COLOR_TYPE_PALETTE, .bit_depth = 4, .palette = palette, .palette_alpha = alpha},
       png_bytes(indexes, 4),
       from_palette(indexes, palette)},
      {"grey1", {.bit_depth = 1}, png_bytes(one_bit, 1), cv::Mat(one_bit * 255)},
      {"grey4", {.bit_depth = 4}, png_bytes(four_bit, 4), cv::Mat(four_bit * 17)},
      {"grey-alpha8",
       {.colour = PNG_COLOR_TYPE_GRAY_ALPHA},
       png_bytes(merged({grey8, alpha8}), 8),
       merged({grey8, grey8, grey8})},
      {"grey-alpha16",
       {.colour = PNG_COLOR_TYPE_GRAY_ALPHA, .bit_depth = 16},
       png_bytes(merged({grey16, alpha16}), 16),
       merged({grey16, grey16, grey16})},
      {"rgb8-adam7",
       {.colour = PNG_COLOR_TYPE_RGB, .interlace = PNG_INTERLACE_ADAM7},
       png_bytes(rgb, 8),
       reversed(rgb)},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const auto path = dir / (c.name + ".png");
    ASSERT_NO_FATAL_FAILURE(write_png_file(path, kWidth, kHeight, c.spec, c.data));
    const cv::Mat whole = io::read_image(path);
    expect_same(whole, c.expected);
    // Only an interlaced PNG is decoded whole: its rows come out at the last pass.
    expect_bands_match(path, whole, c.spec.interlace != PNG_INTERLACE_NONE);
  }
}

// $TMPDIR set for one test, restored after it.
class TemporaryFolder {
 public:
  explicit TemporaryFolder(const std::filesystem::path& dir) {
    if (const char* old = std::getenv("TMPDIR")) old_ = old;
    ::setenv("TMPDIR", dir.c_str(), 1);
  }
  ~TemporaryFolder() {
    if (old_)
      ::setenv("TMPDIR", old_->c_str(), 1);
    else
      ::unsetenv("TMPDIR");
  }
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;

 private:
  std::optional<std::string> old_;
};

// A file decoded whole keeps its rows in an unlinked file in $TMPDIR: the
// bands are the image's, and nothing is left in the folder, even while open.
TEST(HostRowReader, AFileDecodedWholeKeepsItsRowsInAnUnlinkedTemporaryFile) {
  const auto dir = testing::scratch_dir();
  const auto temporary = dir / "tmp";
  std::filesystem::create_directories(temporary);
  const TemporaryFolder scoped(temporary);
  const cv::Mat image = random_image(CV_16UC1, 65536);
  const auto path = dir / "adam7.png";
  ASSERT_NO_FATAL_FAILURE(
      write_png_file(path, kWidth, kHeight,
                     {.colour = PNG_COLOR_TYPE_GRAY, .bit_depth = 16, .interlace = PNG_INTERLACE_ADAM7},
                     png_bytes(image, 16)));
  const auto reader = io::open_row_reader(path);
  EXPECT_TRUE(reader->decoded_whole());
  EXPECT_TRUE(std::filesystem::is_empty(temporary));
  cv::Mat band;
  reader->read(3, 5, band);
  expect_same(band, image.rowRange(3, 8));
  expect_bands_match(path, image, true);
  EXPECT_TRUE(std::filesystem::is_empty(temporary));
}

// Rows appended a band at a time come back in any order, from an unlinked file.
TEST(HostTemporaryRows, BandsAppendedComeBackInAnyOrder) {
  const auto temporary = testing::scratch_dir() / "tmp";
  std::filesystem::create_directories(temporary);
  const TemporaryFolder scoped(temporary);
  const cv::Mat image = random_image(CV_16UC1, 65536);
  io::TemporaryRows rows("image.png", image.cols, image.type(), image.rows);
  for (int y0 = 0; y0 < image.rows; y0 += 7) rows.append(image.rowRange(y0, std::min(y0 + 7, image.rows)));
  EXPECT_EQ(rows.rows(), image.rows);
  EXPECT_TRUE(std::filesystem::is_empty(temporary));
  cv::Mat band;
  for (const int y0 : {image.rows - 4, 0, 5}) {
    rows.read(y0, 4, band);
    expect_same(band, image.rowRange(y0, y0 + 4));
  }
  const TemporaryFolder missing(temporary / "missing");
  const std::string error = error_of([&] { io::TemporaryRows("image.png", 4, CV_32FC1, 8); });
  EXPECT_THAT(error, HasSubstr("image.png: cannot keep its 1 MB of decoded rows"));
  EXPECT_THAT(error, HasSubstr("TMPDIR"));
}

// No temporary folder to keep the rows in: the error names the file and
// $TMPDIR; read once, the rows need none.
TEST(HostRowReader, AFileDecodedWholeWithoutATemporaryFolderSaysSo) {
  const auto dir = testing::scratch_dir();
  const TemporaryFolder scoped(dir / "missing");
  const auto path = dir / "adam7.png";
  ASSERT_NO_FATAL_FAILURE(write_png_file(path, kWidth, kHeight,
                                         {.colour = PNG_COLOR_TYPE_GRAY, .interlace = PNG_INTERLACE_ADAM7},
                                         png_bytes(random_image(CV_8UC1, 256), 8)));
  const std::string error = error_of([&] { io::open_row_reader(path); });
  EXPECT_THAT(error, HasSubstr(path.string()));
  EXPECT_THAT(error, HasSubstr("TMPDIR"));
  // Read once, the file stays in memory and needs no temporary folder.
  cv::Mat rows;
  io::open_row_reader(path, io::RowReading::kOnce)->read(0, kHeight, rows);
  EXPECT_EQ(rows.size(), cv::Size(kWidth, kHeight));
}

TEST(HostRowReader, PfmBandsEqualTheWholeImageInAnyOrder) {
  const auto dir = testing::scratch_dir();
  for (const int type : {CV_32FC1, CV_32FC3}) {
    const cv::Mat image = random_image(type, 4.0);
    const auto path = dir / (type == CV_32FC1 ? "grey.pfm" : "rgb.pfm");
    io::write_pfm(path, image);
    const cv::Mat whole = io::read_image(path);
    expect_same(whole, image);
    expect_bands_match(path, whole);
  }
}

// `header`, then `values` floats (-1, -0.75, -0.5, ...) big-endian in file order (bottom row first).
void write_big_endian_pfm(const std::filesystem::path& path, const std::string& header, int values) {
  std::ofstream out(path, std::ios::binary);
  out << header;
  for (int i = 0; i < values; ++i) {
    const auto bits = std::bit_cast<std::uint32_t>(0.25f * static_cast<float>(i) - 1.0f);
    for (int shift = 24; shift >= 0; shift -= 8) out.put(static_cast<char>((bits >> shift) & 0xffu));
  }
}

TEST(HostRowReader, BigEndianPfmRowsEqualReadPfm) {
  const auto dir = testing::scratch_dir();
  write_big_endian_pfm(dir / "grey.pfm", "Pf\n4 3\n1.0\n", 4 * 3);
  write_big_endian_pfm(dir / "rgb.pfm", "PF\n4 3\n1.0\n", 4 * 3 * 3);
  const cv::Mat grey = io::read_pfm(dir / "grey.pfm");
  const cv::Mat rgb = io::read_pfm(dir / "rgb.pfm");
  ASSERT_EQ(grey.type(), CV_32FC1);
  ASSERT_EQ(rgb.type(), CV_32FC3);
  EXPECT_EQ(grey.at<float>(2, 0), -1.0f);                               // bottom-left: the file's first value
  EXPECT_EQ(grey.at<float>(0, 3), 1.75f);                               // top-right: its last
  EXPECT_EQ(rgb.at<cv::Vec3f>(2, 0), cv::Vec3f(-0.5f, -0.75f, -1.0f));  // BGR in memory
  expect_bands_match(dir / "grey.pfm", grey);
  expect_bands_match(dir / "rgb.pfm", rgb);
}

TEST(HostRowReader, TruncatedPfmIsRefusedWhenOpened) {
  const auto dir = testing::scratch_dir();
  const auto path = dir / "short.pfm";
  io::write_pfm(path, random_image(CV_32FC3, 1.0));
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - 6);
  const std::string error = error_of([&] { io::open_row_reader(path); });
  EXPECT_THAT(error, HasSubstr(path.string()));
  EXPECT_THAT(error, HasSubstr("truncated"));
}

TEST(HostRowReader, TiffBandsCrossStripsAndTilesAsReadTiffReadsThem) {
  const auto dir = testing::scratch_dir();
  const struct {
    const char* name;
    int type;  // of the colour samples, in file order
    Written layout;
  } cases[] = {
      {"rgb16-strips", CV_16UC3, {}},
      {"grey8-deflate",
       CV_8UC1,
       {.bits = 8, .photometric = PHOTOMETRIC_MINISBLACK, .compression = COMPRESSION_ADOBE_DEFLATE}},
      {"rgb8-planar-alpha", CV_8UC3, {.bits = 8, .extra_samples = 1, .planar = true}},
      {"rgb16-tiled", CV_16UC3, {.tile = 16}},
      {"rgb16-planar-tiled-alpha", CV_16UC3, {.extra_samples = 1, .planar = true, .tile = 16}},
      {"grey-float",
       CV_32FC1,
       {.bits = 32, .format = SAMPLEFORMAT_IEEEFP, .photometric = PHOTOMETRIC_MINISBLACK}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const int depth = CV_MAT_DEPTH(c.type);
    const cv::Mat rgb = random_image(c.type, depth == CV_8U ? 256 : depth == CV_16U ? 65536 : 4.0);
    const auto path = dir / (std::string(c.name) + ".tif");
    ASSERT_NO_FATAL_FAILURE(write_tiff(path, rgb, c.layout));
    const cv::Mat whole = io::read_image(path);  // read_tiff, by the name
    expect_same(whole, reversed(rgb));
    expect_bands_match(path, whole);
  }
}

TEST(HostRowReader, RowsOutsideTheImageAreRefusedNamingTheFile) {
  const auto dir = testing::scratch_dir();
  ASSERT_TRUE(cv::imwrite((dir / "frame.png").string(), random_image(CV_8UC3, 256)));
  io::write_pfm(dir / "frame.pfm", random_image(CV_32FC1, 1.0));
  ASSERT_NO_FATAL_FAILURE(write_tiff(dir / "frame.tif", random_image(CV_16UC3, 65536), {}));
  const struct { int y0, rows; } ranges[] = {{-1, 2}, {kHeight - 3, 4}, {kHeight, 1}, {0, 0}, {0, -1}};
  for (const char* name : {"frame.png", "frame.pfm", "frame.tif"}) {
    SCOPED_TRACE(name);
    const auto path = dir / name;
    const auto reader = io::open_row_reader(path);
    cv::Mat band;
    for (const auto& range : ranges) {
      const std::string error = error_of([&] { reader->read(range.y0, range.rows, band); });
      EXPECT_THAT(error, HasSubstr(path.string())) << range.y0 << " + " << range.rows;
      EXPECT_THAT(error, HasSubstr("outside")) << range.y0 << " + " << range.rows;
    }
    // A refused range leaves the reader as it was.
    expect_band(*reader, io::read_image(path), 0, kHeight);
  }
}

TEST(HostRowReader, TruncatedPngOpensAndFailsAtTheRowsItLacks) {
  const auto dir = testing::scratch_dir();
  const auto path = dir / "cut.png";
  // Noise does not compress: the data spans many IDAT chunks.
  const cv::Mat image = random_image(CV_8UC3, 256, {256, 256});
  ASSERT_TRUE(cv::imwrite(path.string(), image));
  expect_bands_match(path, io::read_image(path));

  std::filesystem::resize_file(path, std::filesystem::file_size(path) / 2);
  const auto reader = io::open_row_reader(path);  // the header is all there
  EXPECT_EQ(reader->size(), image.size());
  EXPECT_FALSE(reader->decoded_whole());
  expect_band(*reader, image, 0, 4);  // and so are the first rows
  cv::Mat band;
  const std::string error = error_of([&] { reader->read(200, 56, band); });
  EXPECT_THAT(error, HasSubstr(path.string()));
  EXPECT_THAT(error, HasSubstr("cannot decode"));
}

TEST(HostRowReader, MissingAndNonImageFilesAreRefusedWhenOpened) {
  const auto dir = testing::scratch_dir();
  for (const char* name : {"absent.png", "absent.pfm", "absent.tif"}) {
    const std::string error = error_of([&] { io::open_row_reader(dir / name); });
    EXPECT_THAT(error, HasSubstr((dir / name).string()));
    EXPECT_THAT(error, HasSubstr("no such file"));
  }
  std::ofstream(dir / "text.png") << "this is not a PNG\n";
  EXPECT_THAT(error_of([&] { io::open_row_reader(dir / "text.png"); }),
              HasSubstr((dir / "text.png").string()));
  std::filesystem::create_directory(dir / "folder.png");
  EXPECT_THAT(error_of([&] { io::open_row_reader(dir / "folder.png"); }), HasSubstr("not a regular file"));
}

}  // namespace
}  // namespace lightstage
