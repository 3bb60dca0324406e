// Camera RAW decoding (io/raw_image.hpp) and EXIF (io/exif.hpp), on DNGs the
// simulated DSLR writes (sim/dng_writer.hpp) from the simulator's radiance.
#include "lightstage/host/io/raw_image.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/exif.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/sim/dng_writer.hpp"
#include "lightstage/sim/sensor.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <vector>

namespace lightstage {
namespace {

using testing::error_of;
using ::testing::HasSubstr;

constexpr int kBits = 14;
constexpr double kWhite = (1 << kBits) - 1;

// The channel (0 = R, 1 = G, 2 = B) of each site of a 2×2 pattern.
std::array<int, 4> channels_of(const std::array<char, 4>& cfa) {
  std::array<int, 4> out{};
  for (int s = 0; s < 4; ++s)
    out[static_cast<std::size_t>(s)] = cfa[static_cast<std::size_t>(s)] == 'R'   ? 0
                                       : cfa[static_cast<std::size_t>(s)] == 'G' ? 1
                                                                                 : 2;
  return out;
}

// A colour radiance over the whole sensor range: a ramp in x, a different
// ramp per channel, so every block and channel sees another level.
cv::Mat radiance(int rows, int cols) {
  cv::Mat shading(rows, cols, CV_64FC3);  // BGR
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x) {
      const double t = (x + 0.37 * y) / (cols + 0.37 * rows);
      shading.at<cv::Vec3d>(y, x) = cv::Vec3d(1.6 * t, 1.4 * t, 1.5 * t);  // up to and beyond clipping
    }
  return shading;
}

// The simulator's sensor without noise: DN = black + y · full code, per pixel
// of the chosen channel, plus a site's extra black offset.
struct Mosaic {
  cv::Mat dn;      // CV_16UC1
  cv::Mat linear;  // CV_64FC3 (BGR): y of each pixel, before saturation
};

Mosaic expose_mosaic(const cv::Mat& shading, const std::array<char, 4>& cfa,
                     const std::array<double, 4>& black) {
  sim::SensorOptions options;
  options.noise = sim::NoiseModel::kNone;
  options.bit_depth = kBits;
  options.scale_to_16bit = false;
  options.full_scale_fraction = 0.8;
  CameraDefaults camera;
  const sim::Sensor sensor(options, camera);
  const cv::Mat frame = sensor.expose(shading, 7, 0);  // CV_16UC3, BGR, black level 0
  const auto channel = channels_of(cfa);
  Mosaic m;
  m.dn.create(shading.size(), CV_16UC1);
  m.linear = shading * 0.8;
  for (int y = 0; y < shading.rows; ++y)
    for (int x = 0; x < shading.cols; ++x) {
      const int site = (y % 2) * 2 + x % 2;
      const int c = channel[static_cast<std::size_t>(site)];
      const double value = frame.at<cv::Vec3w>(y, x)[2 - c];
      const double code = std::min(value + black[static_cast<std::size_t>(site)], kWhite);
      m.dn.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(value >= kWhite ? kWhite : code);
    }
  return m;
}

TEST(HostRawImage, HalfSizeIsLinearInTheSimulatorsRadianceOverTheSensorRange) {
  const auto dir = testing::scratch_dir();
  const std::array<double, 4> black = {510, 512, 514, 516};
  for (const std::array<char, 4> cfa :
       {std::array<char, 4>{'R', 'G', 'G', 'B'}, std::array<char, 4>{'G', 'B', 'R', 'G'}}) {
    const cv::Mat shading = radiance(64, 96);
    const Mosaic m = expose_mosaic(shading, cfa, black);
    sim::DngShot shot;
    shot.mosaic = m.dn;
    shot.cfa = cfa;
    shot.black_level = black;
    shot.white_level = kWhite;
    const auto path = dir / "shot.dng";
    sim::write_dng(path, shot);

    const io::RawImage raw = io::read_raw(path);
    ASSERT_EQ(raw.image.type(), CV_16UC3);
    ASSERT_EQ(raw.image.size(), cv::Size(48, 32));
    EXPECT_EQ(raw.mosaic, std::string(cfa.begin(), cfa.end()));
    EXPECT_EQ(raw.demosaic, "half");
    EXPECT_EQ(raw.white, kWhite);

    // Decoded / radiance per block and channel: one constant (the sensor's
    // gain) within 0.5 % wherever the signal is above 2 % and below clipping.
    std::vector<double> ratios;
    int saturated = 0, flagged = 0;
    const auto channel = channels_of(cfa);
    for (int y = 0; y < raw.image.rows; ++y)
      for (int x = 0; x < raw.image.cols; ++x)
        for (int c = 0; c < 3; ++c) {
          double y_mean = 0, n = 0;
          bool clipped = false;
          for (int site = 0; site < 4; ++site) {
            if (channel[static_cast<std::size_t>(site)] != c) continue;
            const int r = 2 * y + site / 2, col = 2 * x + site % 2;
            y_mean += m.linear.at<cv::Vec3d>(r, col)[2 - c];
            n += 1;
            clipped = clipped || m.dn.at<std::uint16_t>(r, col) >= kWhite;
          }
          y_mean /= n;
          const double decoded = raw.image.at<cv::Vec3w>(y, x)[2 - c] / 65535.0;
          if (clipped) {
            ++saturated;
            flagged += decoded == 1.0;
          } else if (y_mean > 0.02) {
            EXPECT_LT(decoded, 1.0);
            ratios.push_back(decoded / y_mean);
          }
        }
    ASSERT_GT(ratios.size(), 3000u);
    ASSERT_GT(saturated, 100);
    EXPECT_EQ(flagged, saturated) << "a clipped site must read 65535 (radiometry's saturation)";
    std::nth_element(ratios.begin(), ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2),
                     ratios.end());
    const double gain = ratios[ratios.size() / 2];
    double worst = 0;
    for (const double r : ratios) worst = std::max(worst, std::abs(r / gain - 1));
    EXPECT_LT(worst, 0.005);
    RecordProperty("worst_relative_deviation", std::to_string(worst));
  }
}

TEST(HostRawImage, DngRoundTripKeepsBlackAndWhiteLevelsExactly) {
  const auto dir = testing::scratch_dir();
  sim::DngShot shot;
  shot.mosaic = cv::Mat(24, 28, CV_16UC1);  // LibRaw takes no side under 22
  cv::randu(shot.mosaic, 1100, 14000);      // above every black level, below white
  shot.cfa = {'B', 'G', 'G', 'R'};
  shot.black_level = {1021, 1024, 1023, 1026};
  shot.white_level = 15000;
  const auto path = dir / "levels.dng";
  sim::write_dng(path, shot);
  const io::RawImage raw = io::read_raw(path);
  // R, first G, B, second G: the B site is first in BGGR, then G, G, R.
  EXPECT_EQ(raw.black[0], 1026);
  EXPECT_EQ(raw.black[1], 1024);
  EXPECT_EQ(raw.black[2], 1021);
  EXPECT_EQ(raw.black[3], 1023);
  EXPECT_EQ(raw.white, 15000);
  // Each output value is its site's (raw − black) / (white − black).
  for (int y = 0; y < raw.image.rows; ++y)
    for (int x = 0; x < raw.image.cols; ++x) {
      const double b = shot.mosaic.at<std::uint16_t>(2 * y, 2 * x);
      const double r = shot.mosaic.at<std::uint16_t>(2 * y + 1, 2 * x + 1);
      const double g = (shot.mosaic.at<std::uint16_t>(2 * y, 2 * x + 1) - 1024.0) / (15000 - 1024) +
                       (shot.mosaic.at<std::uint16_t>(2 * y + 1, 2 * x) - 1023.0) / (15000 - 1023);
      const cv::Vec3w v = raw.image.at<cv::Vec3w>(y, x);
      EXPECT_NEAR(v[0], (b - 1021) / (15000 - 1021) * 65535, 0.5);
      EXPECT_NEAR(v[1], g / 2 * 65535, 0.5);
      EXPECT_NEAR(v[2], (r - 1026) / (15000 - 1026) * 65535, 0.5);
    }
  EXPECT_EQ(raw.describe()["white_level"], 15000);
}

TEST(HostRawImage, FullDemosaicKeepsTheScaleOfHalfSize) {
  const auto dir = testing::scratch_dir();
  sim::DngShot shot;
  shot.mosaic = cv::Mat(32, 32, CV_16UC1, cv::Scalar(2000));  // flat grey: demosaic changes nothing
  shot.black_level = {1000, 1000, 1000, 1000};
  shot.white_level = 11000;
  const auto path = dir / "flat.dng";
  sim::write_dng(path, shot);
  const io::RawImage half = io::read_raw(path, io::RawDemosaic::half);
  const io::RawImage full = io::read_raw(path, io::RawDemosaic::full);
  EXPECT_EQ(full.demosaic, "full");
  EXPECT_EQ(full.image.size(), cv::Size(32, 32));
  EXPECT_EQ(io::read_raw_size(path, io::RawDemosaic::full), cv::Size(32, 32));
  EXPECT_EQ(io::read_raw_size(path), cv::Size(16, 16));
  const cv::Scalar a = cv::mean(half.image), b = cv::mean(full.image(cv::Rect(4, 4, 24, 24)));
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(a[c], 6553.5, 1) << c;
    EXPECT_NEAR(b[c], a[c], 0.01 * a[c]) << c;
  }
  // read_image decodes RAW files at half size.
  EXPECT_EQ(cv::norm(io::read_image(path), half.image, cv::NORM_INF), 0);
}

TEST(HostRawImage, ExifOfTheShotComesBack) {
  const auto dir = testing::scratch_dir();
  sim::DngShot shot;
  shot.mosaic = cv::Mat(24, 24, CV_16UC1, cv::Scalar(100));
  shot.exposure_s = 1.0 / 125;
  shot.iso = 200;
  shot.f_number = 8;
  shot.taken = std::chrono::system_clock::time_point(std::chrono::milliseconds(1764780000123));
  const auto path = dir / "exif.dng";
  sim::write_dng(path, shot);
  const io::ExifInfo exif = io::read_exif(path);
  ASSERT_TRUE(exif.exposure_s && exif.iso && exif.f_number && exif.taken);
  EXPECT_NEAR(*exif.exposure_s, 0.008, 1e-9);
  EXPECT_EQ(*exif.iso, 200);
  EXPECT_NEAR(*exif.f_number, 8, 1e-9);
  EXPECT_EQ(*exif.taken, "2025-12-03T16:40:00.123");
  EXPECT_EQ(exif.make, "Lightstage");
  EXPECT_EQ(exif.to_json()["iso"], 200);
  EXPECT_EQ(io::read_raw(path).camera, "Lightstage Simulated DSLR");

  // Text fields are ASCII by the specification, not always in the file: what
  // reaches a manifest (JSON) is printable ASCII.
  shot.make = "Cam\x97ra\x01";
  sim::write_dng(path, shot);
  EXPECT_EQ(io::read_exif(path).make, "Cam?ra?");
  EXPECT_NO_THROW((void)io::read_exif(path).to_json().dump());
  EXPECT_EQ(io::read_raw(path).camera.substr(0, 6), "Cam?ra");

  // A PNG has no EXIF: empty, not an error.
  const auto png = dir / "plain.png";
  io::write_png(png, cv::Mat(4, 4, CV_16UC1, cv::Scalar(5)));
  EXPECT_TRUE(io::read_exif(png).empty());
}

TEST(HostRawImage, AStackFolderMayListRawFilesDirectly) {
  const auto dir = testing::scratch_dir();
  std::ofstream names(dir / "filenames.txt"), lights(dir / "light_directions.txt");
  for (int i = 0; i < 3; ++i) {
    sim::DngShot shot;
    shot.mosaic = cv::Mat(24, 32, CV_16UC1, cv::Scalar(1000 + 1000 * i));
    shot.white_level = 16383;
    const std::string name = fmt::format("IMG_{}.dng", i);
    sim::write_dng(dir / name, shot);
    names << name << "\n";
    lights << "0 0.1 " << 1 + i << "\n";
  }
  names.close();
  lights.close();
  const ImageStack stack = io::load_stack(dir);
  ASSERT_EQ(stack.frames.size(), 3u);
  EXPECT_EQ(stack.frames[2].image.type(), CV_16UC3);
  EXPECT_EQ(stack.frames[2].image.size(), cv::Size(16, 12));
  EXPECT_NEAR(cv::mean(stack.frames[2].image)[1], 3000.0 / 16383 * 65535, 1);
}

TEST(HostRawImage, BrokenFilesAreRefusedNamingTheFile) {
  const auto dir = testing::scratch_dir();
  EXPECT_THAT(error_of([&] { io::read_raw(dir / "absent.cr2"); }), HasSubstr("no such file"));
  const auto junk = dir / "junk.nef";
  std::ofstream(junk) << "not a raw file, just text long enough to be looked at by a raw decoder";
  const std::string error = error_of([&] { io::read_raw(junk); });
  EXPECT_THAT(error, HasSubstr(junk.string()));
  EXPECT_THAT(error, HasSubstr("not a RAW file"));
  EXPECT_THAT(error_of([&] { io::read_exif(dir / "absent.jpg"); }), HasSubstr("no such file"));
  EXPECT_THAT(error_of([&] { io::read_exif(junk); }), HasSubstr(junk.string()));

  // A DNG cut inside its pixels.
  sim::DngShot shot;
  shot.mosaic = cv::Mat(64, 64, CV_16UC1, cv::Scalar(300));
  const auto whole = dir / "whole.dng";
  sim::write_dng(whole, shot);
  std::ifstream in(whole, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto cut = dir / "cut.dng";
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() / 3);
  EXPECT_THAT(error_of([&] { io::read_raw(cut); }), HasSubstr(cut.string()));

  EXPECT_THAT(error_of([] { io::parse_raw_demosaic("quarter", "--raw-demosaic"); }),
              HasSubstr("--raw-demosaic: 'quarter'"));
  EXPECT_TRUE(io::is_raw_file("a/B.CR3"));
  EXPECT_FALSE(io::is_raw_file("a/b.png"));
}

}  // namespace
}  // namespace lightstage
