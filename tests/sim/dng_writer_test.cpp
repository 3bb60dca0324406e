// The simulated DSLR's DNG files, read back by the readers the host uses for
// real cameras: LibRaw (the mosaic, levels, CFA pattern and shot data as a raw
// converter sees them) and exiv2 (every tag as written).
#include "lightstage/sim/dng_writer.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/testing/errors.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <libraw/libraw.h>
#include <sys/resource.h>
#include <tiffio.h>
#include <exiv2/exiv2.hpp>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace lightstage::sim {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// 2024-03-05 07:08:09.123 UTC.
const std::chrono::system_clock::time_point kTaken{std::chrono::milliseconds(1709622489123LL)};
constexpr std::time_t kTakenSeconds = 1709622489;

// A mosaic whose every pixel differs from its neighbours, over the full 16-bit range.
cv::Mat random_mosaic(int rows, int cols, unsigned seed) {
  cv::Mat mosaic(rows, cols, CV_16UC1);
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> value(0, 65535);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) mosaic.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(value(random));
  }
  return mosaic;
}

DngShot example_shot(const std::string& cfa) {
  DngShot shot;
  // 300 rows of 512 bytes: three strips of 128 rows, the last one short.
  shot.mosaic = random_mosaic(300, 256, 7);
  for (std::size_t site = 0; site < 4; ++site) shot.cfa[site] = cfa.at(site);
  shot.black_level = {256, 258, 263, 271};  // a different level at each site, both greens included
  shot.white_level = 16383;
  shot.make = "Lightstage";
  shot.model = "Test DSLR";
  shot.exposure_s = 1.0 / 250;
  shot.iso = 400;
  shot.f_number = 5.6;
  shot.taken = kTaken;
  return shot;
}

// A fresh folder under the system's temporary directory, removed afterwards.
class DngWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "lightstage-dng-test-XXXXXX").string();
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  std::vector<std::string> files_in_dir() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) names.push_back(entry.path().filename().string());
    return names;
  }

  fs::path dir_;
};

// TZ=UTC while alive: LibRaw turns EXIF DateTimeOriginal into a time_t with
// mktime(), i.e. as local time.
class ScopedUtc {
 public:
  ScopedUtc() {
    if (const char* tz = std::getenv("TZ")) old_ = tz;
    ::setenv("TZ", "UTC", 1);
    ::tzset();
  }
  ScopedUtc(const ScopedUtc&) = delete;
  ScopedUtc& operator=(const ScopedUtc&) = delete;
  ~ScopedUtc() {
    if (old_) {
      ::setenv("TZ", old_->c_str(), 1);
    } else {
      ::unsetenv("TZ");
    }
    ::tzset();
  }

 private:
  std::optional<std::string> old_;
};

// The black level LibRaw 0.20 applies at (row, col) of the visible image. It
// keeps DNG levels in three parts: a common `black`, one per colour in
// cblack[0..3] (indexed by COLOR(), 3 being the second green) and a pattern of
// cblack[4] rows by cblack[5] columns in cblack[6...]. After unpack() a 2x2
// BlackLevelRepeatDim is in the pattern, row-major, one value per CFA site
// (LibRaw folds it into the per-colour part only when it processes the image).
unsigned libraw_black_at(LibRaw& raw, int row, int col) {
  const auto& color = raw.imgdata.color;
  unsigned black = color.black + color.cblack[raw.COLOR(row, col)];
  const unsigned pattern_rows = color.cblack[4];
  const unsigned pattern_cols = color.cblack[5];
  if (pattern_rows > 0 && pattern_cols > 0) {
    black += color.cblack[6 + (static_cast<unsigned>(row) % pattern_rows) * pattern_cols +
                          static_cast<unsigned>(col) % pattern_cols];
  }
  return black;
}

// --- LibRaw -------------------------------------------------------------------------

class DngWriterLibRawTest : public DngWriterTest, public ::testing::WithParamInterface<const char*> {};

TEST_P(DngWriterLibRawTest, ReadsBackTheMosaicLevelsPatternAndShot) {
  const DngShot shot = example_shot(GetParam());
  const fs::path path = dir_ / "shot.dng";
  write_dng(path, shot);
  EXPECT_THAT(files_in_dir(), ::testing::ElementsAre("shot.dng"));  // no temporary left beside it

  const ScopedUtc utc;
  auto raw = std::make_unique<LibRaw>();
  ASSERT_EQ(raw->open_file(path.c_str()), LIBRAW_SUCCESS);
  ASSERT_EQ(raw->unpack(), LIBRAW_SUCCESS);
  const auto& data = raw->imgdata;

  EXPECT_EQ(data.idata.dng_version, 0x01040000u);
  EXPECT_STREQ(data.idata.make, "Lightstage");
  EXPECT_STREQ(data.idata.model, "Test DSLR");

  // The whole mosaic is the visible image, pixel for pixel.
  ASSERT_EQ(data.sizes.raw_width, shot.mosaic.cols);
  ASSERT_EQ(data.sizes.raw_height, shot.mosaic.rows);
  EXPECT_EQ(data.sizes.width, shot.mosaic.cols);
  EXPECT_EQ(data.sizes.height, shot.mosaic.rows);
  ASSERT_EQ(data.sizes.left_margin, 0);
  ASSERT_EQ(data.sizes.top_margin, 0);
  ASSERT_NE(data.rawdata.raw_image, nullptr);
  const std::size_t pitch = data.sizes.raw_pitch / sizeof(std::uint16_t);
  int differing = 0;
  for (int y = 0; y < shot.mosaic.rows; ++y) {
    for (int x = 0; x < shot.mosaic.cols; ++x) {
      const std::uint16_t read = data.rawdata.raw_image[static_cast<std::size_t>(y) * pitch + x];
      if (read != shot.mosaic.at<std::uint16_t>(y, x) && ++differing <= 5) {
        ADD_FAILURE() << "pixel (" << x << ", " << y << "): read " << read << ", wrote "
                      << shot.mosaic.at<std::uint16_t>(y, x);
      }
    }
  }
  EXPECT_EQ(differing, 0);

  // Levels and the CFA pattern, at every site of two repeats of the 2x2 cell.
  EXPECT_EQ(data.color.maximum, 16383u);
  EXPECT_EQ(data.idata.colors, 3);
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 4; ++x) {
      const std::size_t site = static_cast<std::size_t>((y % 2) * 2 + x % 2);
      const int colour = raw->COLOR(y, x);
      ASSERT_GE(colour, 0);
      ASSERT_LT(colour, 4);
      EXPECT_EQ(data.idata.cdesc[colour], shot.cfa[site]) << "CFA at (" << x << ", " << y << ")";
      EXPECT_EQ(libraw_black_at(*raw, y, x), static_cast<unsigned>(shot.black_level[site]))
          << "black level at (" << x << ", " << y << ")";
    }
  }

  // The shot, from the EXIF IFD.
  EXPECT_FLOAT_EQ(data.other.shutter, 1.0f / 250);
  EXPECT_FLOAT_EQ(data.other.iso_speed, 400);
  EXPECT_FLOAT_EQ(data.other.aperture, 5.6f);
  EXPECT_EQ(data.other.timestamp, kTakenSeconds);
}

INSTANTIATE_TEST_SUITE_P(Patterns, DngWriterLibRawTest, ::testing::Values("RGGB", "BGGR", "GRBG", "GBRG"));

TEST_F(DngWriterTest, WritesAnRoiOfALargerImage) {
  const cv::Mat full = random_mosaic(64, 80, 11);
  DngShot shot;
  shot.mosaic = full(cv::Rect(3, 5, 48, 40));  // not continuous
  ASSERT_FALSE(shot.mosaic.isContinuous());
  const fs::path path = dir_ / "roi.dng";
  write_dng(path, shot);

  auto raw = std::make_unique<LibRaw>();
  ASSERT_EQ(raw->open_file(path.c_str()), LIBRAW_SUCCESS);
  ASSERT_EQ(raw->unpack(), LIBRAW_SUCCESS);
  ASSERT_EQ(raw->imgdata.sizes.raw_width, 48);
  ASSERT_EQ(raw->imgdata.sizes.raw_height, 40);
  const std::size_t pitch = raw->imgdata.sizes.raw_pitch / sizeof(std::uint16_t);
  int differing = 0;
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 48; ++x) {
      differing += raw->imgdata.rawdata.raw_image[static_cast<std::size_t>(y) * pitch + x] !=
                   full.at<std::uint16_t>(y + 5, x + 3);
    }
  }
  EXPECT_EQ(differing, 0);
  EXPECT_EQ(raw->imgdata.color.maximum, 65535u);  // the defaults
  EXPECT_EQ(libraw_black_at(*raw, 0, 0), 0u);
}

TEST_F(DngWriterTest, ReplacesAnExistingFile) {
  const fs::path path = dir_ / "shot.dng";
  DngShot first;
  first.mosaic = cv::Mat(24, 32, CV_16UC1, cv::Scalar(100));
  write_dng(path, first);
  DngShot second;
  second.mosaic = cv::Mat(40, 48, CV_16UC1, cv::Scalar(200));
  write_dng(path, second);
  EXPECT_THAT(files_in_dir(), ::testing::ElementsAre("shot.dng"));

  auto raw = std::make_unique<LibRaw>();
  ASSERT_EQ(raw->open_file(path.c_str()), LIBRAW_SUCCESS);
  ASSERT_EQ(raw->unpack(), LIBRAW_SUCCESS);
  EXPECT_EQ(raw->imgdata.sizes.raw_width, 48);
  EXPECT_EQ(raw->imgdata.rawdata.raw_image[0], 200);
}

// --- exiv2 --------------------------------------------------------------------------

// exiv2's view of a file's tags; fails the test when a key is missing.
class Exif {
 public:
  explicit Exif(const fs::path& path) : image_(Exiv2::ImageFactory::open(path.string())) {
    image_->readMetadata();
  }
  bool has(const std::string& key) const { return find(key) != nullptr; }
  const Exiv2::Exifdatum& at(const std::string& key) const {
    const Exiv2::Exifdatum* datum = find(key);
    if (datum == nullptr) throw std::runtime_error("no " + key);
    return *datum;
  }
  std::vector<double> numbers(const std::string& key) const {
    const Exiv2::Exifdatum& datum = at(key);
    std::vector<double> values;
    for (long i = 0; i < datum.count(); ++i) values.push_back(datum.toFloat(i));
    return values;
  }

 private:
  const Exiv2::Exifdatum* find(const std::string& key) const {
    Exiv2::ExifData& data = image_->exifData();
    const auto it = data.findKey(Exiv2::ExifKey(key));
    return it == data.end() ? nullptr : &*it;
  }
  decltype(Exiv2::ImageFactory::open(std::string())) image_;
};

TEST_F(DngWriterTest, Exiv2ReadsTheExif) {
  const fs::path path = dir_ / "shot.dng";
  write_dng(path, example_shot("RGGB"));
  const Exif exif(path);
  EXPECT_NEAR(exif.at("Exif.Photo.ExposureTime").toFloat(), 1.0 / 250, 1e-9);
  EXPECT_NEAR(exif.at("Exif.Photo.FNumber").toFloat(), 5.6, 1e-6);
  EXPECT_EQ(exif.at("Exif.Photo.ISOSpeedRatings").toLong(), 400);
  EXPECT_EQ(exif.at("Exif.Photo.DateTimeOriginal").toString(), "2024:03:05 07:08:09");
  EXPECT_EQ(exif.at("Exif.Photo.SubSecTimeOriginal").toString(), "123");
}

TEST_F(DngWriterTest, Exiv2ReadsEveryDngTag) {
  const fs::path path = dir_ / "shot.dng";
  write_dng(path, example_shot("GBRG"));
  const Exif exif(path);
  EXPECT_EQ(exif.at("Exif.Image.NewSubfileType").toLong(), 0);
  EXPECT_EQ(exif.at("Exif.Image.ImageWidth").toLong(), 256);
  EXPECT_EQ(exif.at("Exif.Image.ImageLength").toLong(), 300);
  EXPECT_EQ(exif.at("Exif.Image.BitsPerSample").toLong(), 16);
  EXPECT_EQ(exif.at("Exif.Image.SamplesPerPixel").toLong(), 1);
  EXPECT_EQ(exif.at("Exif.Image.Compression").toLong(), 1);
  EXPECT_EQ(exif.at("Exif.Image.PhotometricInterpretation").toLong(), 32803);
  EXPECT_EQ(exif.at("Exif.Image.PlanarConfiguration").toLong(), 1);
  EXPECT_EQ(exif.at("Exif.Image.Orientation").toLong(), 1);
  EXPECT_EQ(exif.at("Exif.Image.Make").toString(), "Lightstage");
  EXPECT_EQ(exif.at("Exif.Image.Model").toString(), "Test DSLR");
  EXPECT_EQ(exif.at("Exif.Image.UniqueCameraModel").toString(), "Lightstage Test DSLR");
  EXPECT_THAT(exif.numbers("Exif.Image.DNGVersion"), ::testing::ElementsAre(1, 4, 0, 0));
  EXPECT_THAT(exif.numbers("Exif.Image.DNGBackwardVersion"), ::testing::ElementsAre(1, 1, 0, 0));
  EXPECT_THAT(exif.numbers("Exif.Image.CFARepeatPatternDim"), ::testing::ElementsAre(2, 2));
  EXPECT_THAT(exif.numbers("Exif.Image.CFAPattern"), ::testing::ElementsAre(1, 2, 0, 1));  // G B R G
  EXPECT_THAT(exif.numbers("Exif.Image.CFAPlaneColor"), ::testing::ElementsAre(0, 1, 2));
  EXPECT_EQ(exif.at("Exif.Image.CFALayout").toLong(), 1);
  EXPECT_THAT(exif.numbers("Exif.Image.BlackLevelRepeatDim"), ::testing::ElementsAre(2, 2));
  EXPECT_THAT(exif.numbers("Exif.Image.BlackLevel"), ::testing::ElementsAre(256, 258, 263, 271));
  EXPECT_THAT(exif.numbers("Exif.Image.WhiteLevel"), ::testing::ElementsAre(16383));
  EXPECT_THAT(exif.numbers("Exif.Image.ColorMatrix1"), ::testing::ElementsAre(1, 0, 0, 0, 1, 0, 0, 0, 1));
  EXPECT_EQ(exif.at("Exif.Image.CalibrationIlluminant1").toLong(), 21);
  EXPECT_THAT(exif.numbers("Exif.Image.AsShotNeutral"), ::testing::ElementsAre(1, 1, 1));
  EXPECT_FALSE(exif.has("Exif.Image.SubIFDs"));

  // One IFD in the chain: no thumbnail, no second image.
  const std::unique_ptr<TIFF, void (*)(TIFF*)> tiff(TIFFOpen(path.c_str(), "r"), &TIFFClose);
  ASSERT_NE(tiff, nullptr);
  EXPECT_EQ(TIFFNumberOfDirectories(tiff.get()), 1);
}

TEST_F(DngWriterTest, FractionalBlackLevelsAreWrittenExactly) {
  DngShot shot;
  shot.mosaic = cv::Mat(24, 24, CV_16UC1, cv::Scalar(0));
  shot.black_level = {64.5, 64.25, 64.75, 1023};
  shot.white_level = 1023.6;  // rounded: WhiteLevel is an integer
  const fs::path path = dir_ / "shot.dng";
  write_dng(path, shot);
  const Exif exif(path);
  EXPECT_THAT(exif.numbers("Exif.Image.BlackLevel"), ::testing::ElementsAre(64.5, 64.25, 64.75, 1023));
  EXPECT_THAT(exif.numbers("Exif.Image.WhiteLevel"), ::testing::ElementsAre(1024));
}

TEST_F(DngWriterTest, UnknownShotDataIsLeftOut) {
  DngShot shot;
  shot.mosaic = cv::Mat(24, 24, CV_16UC1, cv::Scalar(0));
  const fs::path path = dir_ / "shot.dng";
  write_dng(path, shot);
  const Exif exif(path);
  EXPECT_TRUE(exif.has("Exif.Image.DNGVersion"));
  EXPECT_FALSE(exif.has("Exif.Image.ExifTag"));  // no EXIF IFD at all
  EXPECT_FALSE(exif.has("Exif.Photo.ExposureTime"));
  EXPECT_FALSE(exif.has("Exif.Photo.ISOSpeedRatings"));
  EXPECT_FALSE(exif.has("Exif.Photo.FNumber"));
  EXPECT_FALSE(exif.has("Exif.Photo.DateTimeOriginal"));

  // Some known, some not.
  shot.iso = 99999;  // above what ISOSpeedRatings holds
  shot.taken = std::chrono::system_clock::time_point(std::chrono::microseconds(1709622489999999LL));
  write_dng(path, shot);
  const Exif partial(path);
  EXPECT_EQ(partial.at("Exif.Photo.ISOSpeedRatings").toLong(), 65535);
  EXPECT_EQ(partial.at("Exif.Photo.DateTimeOriginal").toString(), "2024:03:05 07:08:09");
  EXPECT_EQ(partial.at("Exif.Photo.SubSecTimeOriginal").toString(), "999");  // truncated, not rounded up
  EXPECT_FALSE(partial.has("Exif.Photo.ExposureTime"));
  EXPECT_FALSE(partial.has("Exif.Photo.FNumber"));
}

// --- Errors -------------------------------------------------------------------------

struct BadShot {
  const char* name;
  std::function<void(DngShot&)> spoil;
  const char* message;
};
void PrintTo(const BadShot& bad, std::ostream* out) { *out << bad.name; }

std::function<void(DngShot&)> with_cfa(const char* pattern) {
  return [pattern](DngShot& shot) { std::copy_n(pattern, 4, shot.cfa.begin()); };
}

class DngWriterRejectsTest : public DngWriterTest, public ::testing::WithParamInterface<BadShot> {};

TEST_P(DngWriterRejectsTest, NamingTheFileAndLeavingNothing) {
  DngShot shot = example_shot("RGGB");
  GetParam().spoil(shot);
  const fs::path path = dir_ / "bad.dng";
  const std::string error = testing::error_of([&] { write_dng(path, shot); });
  EXPECT_THAT(error, HasSubstr(path.string() + ": cannot write a DNG: "));
  EXPECT_THAT(error, HasSubstr(GetParam().message));
  EXPECT_THAT(files_in_dir(), ::testing::IsEmpty());
}

INSTANTIATE_TEST_SUITE_P(
    Shots, DngWriterRejectsTest,
    ::testing::Values(
        BadShot{"EightBit", [](DngShot& s) { s.mosaic = cv::Mat(24, 24, CV_8UC1, cv::Scalar(0)); },
                "the mosaic is CV_8UC1, not CV_16UC1"},
        BadShot{"ThreeChannels", [](DngShot& s) { s.mosaic = cv::Mat(24, 24, CV_16UC3, cv::Scalar(0)); },
                "the mosaic is CV_16UC3, not CV_16UC1"},
        BadShot{"Empty", [](DngShot& s) { s.mosaic = cv::Mat(0, 0, CV_16UC1); }, "the mosaic is 0x0"},
        BadShot{"OddWidth", [](DngShot& s) { s.mosaic = cv::Mat(24, 25, CV_16UC1, cv::Scalar(0)); },
                "the mosaic is 25x24; its width and height must be even"},
        BadShot{"OddHeight", [](DngShot& s) { s.mosaic = cv::Mat(23, 24, CV_16UC1, cv::Scalar(0)); },
                "the mosaic is 24x23; its width and height must be even"},
        BadShot{"LetterX", with_cfa("RGXB"), "CFA letter 'X' in \"RGXB\""},
        BadShot{"LowerCase", with_cfa("rggb"), "CFA letter 'r' in \"rggb\""},
        BadShot{"TwoReds", with_cfa("RRGB"), "CFA pattern \"RRGB\" must have exactly one R, two G and one B"},
        BadShot{"ThreeGreens", with_cfa("GGGB"),
                "CFA pattern \"GGGB\" must have exactly one R, two G and one B"},
        BadShot{"NoBlue", with_cfa("RGGG"), "CFA pattern \"RGGG\" must have exactly one R, two G and one B"},
        BadShot{"TwoBlues", with_cfa("RGBB"),
                "CFA pattern \"RGBB\" must have exactly one R, two G and one B"},
        BadShot{"BlackAtWhite", [](DngShot& s) { s.black_level[2] = s.white_level; },
                "black level 16383 of CFA site 2 ('G') must be >= 0 and below the white level 16383"},
        BadShot{"BlackAboveWhite", [](DngShot& s) { s.black_level[3] = 20000; },
                "black level 20000 of CFA site 3 ('B')"},
        BadShot{"NegativeBlack", [](DngShot& s) { s.black_level[0] = -1; },
                "black level -1 of CFA site 0 ('R')"},
        BadShot{"WhiteZero", [](DngShot& s) { s.white_level = 0; }, "white level 0 is outside 1..65535"},
        BadShot{"WhiteAbove16Bit", [](DngShot& s) { s.white_level = 70000; },
                "white level 70000 is outside 1..65535"},
        BadShot{"NegativeExposure", [](DngShot& s) { s.exposure_s = -0.01; }, "exposure_s -0.01 must be"},
        BadShot{"NanIso", [](DngShot& s) { s.iso = std::nan(""); }, "iso nan must be"},
        BadShot{"InfiniteFNumber", [](DngShot& s) { s.f_number = HUGE_VAL; }, "f_number inf must be"}),
    [](const ::testing::TestParamInfo<BadShot>& param) { return std::string(param.param.name); });

TEST_F(DngWriterTest, AMissingFolderIsAnErrorNamingTheFile) {
  const fs::path path = dir_ / "missing" / "shot.dng";
  const std::string error = testing::error_of([&] { write_dng(path, example_shot("RGGB")); });
  EXPECT_THAT(error, HasSubstr(path.string() + ": cannot write: "));
  EXPECT_THAT(error, HasSubstr("No such file or directory"));
  EXPECT_FALSE(fs::exists(dir_ / "missing"));
  EXPECT_THAT(files_in_dir(), ::testing::IsEmpty());
}

TEST_F(DngWriterTest, AFailedRenameLeavesNoTemporary) {
  // The target is a folder (not empty): everything but the rename succeeds.
  const fs::path path = dir_ / "shot.dng";
  fs::create_directory(path);
  std::ofstream(path / "keep") << "x";
  const std::string error = testing::error_of([&] { write_dng(path, example_shot("RGGB")); });
  EXPECT_THAT(error, HasSubstr(path.string() + ": cannot write: "));
  EXPECT_THAT(files_in_dir(), ::testing::ElementsAre("shot.dng"));
  EXPECT_TRUE(fs::is_directory(path));
}

// In a death-test child: files larger than 16 KiB fail with EFBIG (SIGXFSZ
// ignored), so the pixels of a 300x256 mosaic (150 KiB) cannot all be
// written. Exits 0 when the error names the file and the folder is empty.
[[noreturn]] void write_beyond_file_size_limit(const fs::path& dir) {
  std::signal(SIGXFSZ, SIG_IGN);
  const rlimit limit{16 * 1024, 16 * 1024};
  ::setrlimit(RLIMIT_FSIZE, &limit);
  const fs::path path = dir / "shot.dng";
  const std::string error = testing::error_of([&] { write_dng(path, example_shot("RGGB")); });
  const bool empty = fs::is_empty(dir);
  std::cerr << error << "\n" << (empty ? "folder empty" : "folder not empty") << "\n";
  std::_Exit(error.rfind(path.string() + ": cannot write: File too large", 0) == 0 && empty ? 0 : 1);
}

TEST_F(DngWriterTest, AWriteErrorPartWayLeavesNothing) {
  EXPECT_EXIT(write_beyond_file_size_limit(dir_), ::testing::ExitedWithCode(0),
              "cannot write: File too large\nfolder empty");
  EXPECT_THAT(files_in_dir(), ::testing::IsEmpty());
}

}  // namespace
}  // namespace lightstage::sim
