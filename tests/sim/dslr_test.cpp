// The simulated DSLR on the remote-release port: presses fed as timeline
// entries, shots read back from the folder with LibRaw and exiv2, as the host
// reads a real camera's files.
#include "lightstage/sim/camera/dslr.hpp"

#include "lightstage/common/camera.hpp"
#include "lightstage/common/clock.hpp"
#include "lightstage/testing/errors.hpp"
#include "test_rig.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <libraw/libraw.h>
#include <exiv2/exiv2.hpp>

#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace lightstage::sim {
namespace {

namespace fs = std::filesystem;
using gpio::TimelineEntry;
using ::testing::HasSubstr;

constexpr std::int64_t kMs = 1'000'000;

TimelineEntry led(std::int64_t t, int id, int value) {
  return {t, "LED" + std::to_string(id), value, id, ""};
}

// A 100 us press of the remote release at t.
std::vector<TimelineEntry> shutter(std::int64_t t) {
  return {{t, "TRIGGER", 1, -1, ""}, {t + 100'000, "TRIGGER", 0, -1, ""}};
}

// What LibRaw reads from a DNG: the mosaic, the black level at each site of
// the 2x2 pattern (LibRaw 0.20 keeps a 2x2 BlackLevelRepeatDim in
// cblack[6...], see dng_writer_test.cpp) and the white level.
struct RawFile {
  cv::Mat mosaic;  // CV_16UC1
  std::array<double, 4> black{};
  double white = 0;
  std::string cfa;  // the 2x2 pattern's letters, row-major
};

RawFile read_raw(const fs::path& path) {
  auto raw = std::make_unique<LibRaw>();
  EXPECT_EQ(raw->open_file(path.c_str()), LIBRAW_SUCCESS) << path;
  EXPECT_EQ(raw->unpack(), LIBRAW_SUCCESS) << path;
  const auto& data = raw->imgdata;
  RawFile file;
  file.mosaic = cv::Mat(data.sizes.raw_height, data.sizes.raw_width, CV_16UC1);
  const std::size_t pitch = data.sizes.raw_pitch / sizeof(std::uint16_t);
  for (int y = 0; y < file.mosaic.rows; ++y) {
    for (int x = 0; x < file.mosaic.cols; ++x)
      file.mosaic.at<std::uint16_t>(y, x) = data.rawdata.raw_image[static_cast<std::size_t>(y) * pitch + x];
  }
  const auto& color = data.color;
  for (int site = 0; site < 4; ++site) {
    const int y = site / 2, x = site % 2;
    unsigned black = color.black + color.cblack[raw->COLOR(y, x)];
    if (color.cblack[4] > 0 && color.cblack[5] > 0) {
      black += color.cblack[6 + (static_cast<unsigned>(y) % color.cblack[4]) * color.cblack[5] +
                            static_cast<unsigned>(x) % color.cblack[5]];
    }
    file.black[static_cast<std::size_t>(site)] = black;
    file.cfa += data.idata.cdesc[raw->COLOR(y, x)];
  }
  file.white = color.maximum;
  return file;
}

// Half-size decode: each 2x2 block → (R, mean G, B) of (raw − black)/(white − black).
std::array<cv::Mat, 3> half_size(const RawFile& file) {
  const int rows = file.mosaic.rows / 2, cols = file.mosaic.cols / 2;
  std::array<cv::Mat, 3> rgb;
  for (auto& plane : rgb) plane = cv::Mat(rows, cols, CV_64F, cv::Scalar(0));
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      for (int site = 0; site < 4; ++site) {
        const auto s = static_cast<std::size_t>(site);
        const double value =
            (file.mosaic.at<std::uint16_t>(2 * y + site / 2, 2 * x + site % 2) - file.black[s]) /
            (file.white - file.black[s]);
        const char letter = file.cfa[s];
        const int plane = letter == 'R' ? 0 : letter == 'G' ? 1 : 2;
        rgb[static_cast<std::size_t>(plane)].at<double>(y, x) += letter == 'G' ? value / 2 : value;
      }
    }
  }
  return rgb;
}

// DateTimeOriginal + SubSecTimeOriginal as nanoseconds since the epoch (UTC).
std::int64_t exif_time_ns(const fs::path& path) {
  auto image = Exiv2::ImageFactory::open(path.string());
  image->readMetadata();
  const auto& exif = image->exifData();
  const std::string date = exif.findKey(Exiv2::ExifKey("Exif.Photo.DateTimeOriginal"))->toString();
  const std::string subsec = exif.findKey(Exiv2::ExifKey("Exif.Photo.SubSecTimeOriginal"))->toString();
  std::tm tm{};
  EXPECT_NE(::strptime(date.c_str(), "%Y:%m:%d %H:%M:%S", &tm), nullptr) << date;
  return static_cast<std::int64_t>(::timegm(&tm)) * 1'000'000'000 + std::stoll(subsec) * kMs;
}

class DslrTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "lightstage-dslr-test-XXXXXX").string();
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
    rig_ = testing::make_rig({{0, 0, 300}, {200, 0, 220}}, 32, 32, 3.2);
    scene_.scene = "matte-sphere";
    scene_.light_model = LightModel::kDistant;
    scene_.threads = 1;
    scene_.sensor.black_level = 512;
    options_.folder = dir_;
    options_.lag_min_ns = 5 * kMs;
    options_.lag_max_ns = 15 * kMs;
    options_.delay_min_ns = 10 * kMs;
    options_.delay_max_ns = 60 * kMs;
  }
  void TearDown() override {
    dslr_.reset();
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  SimulatedDslr& start() {
    world_ = std::make_shared<World>(rig_, scene_);
    dslr_ = std::make_shared<SimulatedDslr>(world_, scene_.sensor, options_);
    return *dslr_;
  }
  void feed(const std::vector<TimelineEntry>& entries) { dslr_->record(entries); }
  // Waits (at most 4 s) until every taken shot is on the card or lost.
  DslrStats settle() {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(4);
    DslrStats stats = dslr_->stats();
    while (stats.written + stats.dropped + stats.failed < stats.taken &&
           std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      stats = dslr_->stats();
    }
    return stats;
  }
  // The folder's files, without the hidden temporaries a write goes through.
  std::set<std::string> files() const {
    std::set<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      const std::string name = entry.path().filename().string();
      if (!name.starts_with(".")) names.insert(name);
    }
    return names;
  }

  fs::path dir_;
  Rig rig_;
  SimulateOptions scene_;
  DslrOptions options_;
  std::shared_ptr<World> world_;
  std::shared_ptr<SimulatedDslr> dslr_;
};

TEST_F(DslrTest, OnePressGivesOneRawFileWithTheSimCamerasLevels) {
  SimulatedDslr& dslr = start();
  const std::int64_t t = monotonic_now_ns();
  const std::int64_t edge_realtime_ns =
      camera::convert_timestamp_ns(t, camera::ClockDomain::kMonotonic, camera::ClockDomain::kRealtime);
  feed({led(t - 10 * kMs, 1, 1)});
  feed(shutter(t));
  feed({led(t + 40 * kMs, 1, 0)});  // lit well past the latest window's end
  // Nothing on the card before the exposure has ended and the card delay passed.
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_TRUE(files().empty());
  const DslrStats stats = settle();
  EXPECT_EQ(stats.taken, 1u);
  EXPECT_EQ(stats.written, 1u);
  ASSERT_EQ(files(), std::set<std::string>{"IMG_0001.DNG"});
  EXPECT_GE(monotonic_now_ns(), t + options_.lag_min_ns + 10 * kMs + options_.delay_min_ns);

  const fs::path path = dir_ / "IMG_0001.DNG";
  const RawFile raw = read_raw(path);
  EXPECT_EQ(raw.mosaic.cols, 64);
  EXPECT_EQ(raw.mosaic.rows, 64);
  EXPECT_EQ(raw.cfa, "RGGB");
  EXPECT_THAT(raw.black, ::testing::ElementsAre(512, 514, 516, 518));
  EXPECT_EQ(raw.white, 65535);
  EXPECT_EQ(raw.white, dslr.white_level());

  // The `sim:` camera's frame of the same light: noiseless, and with its own noise.
  SensorOptions sensor = scene_.sensor;
  sensor.noise = NoiseModel::kNone;
  const Sensor clean(sensor, rig_.camera);
  const Sensor noisy(scene_.sensor, rig_.camera);
  const cv::Mat shading = world_->render({{0, 1.0}});
  cv::Mat expected, sim_frame;
  clean.expose(shading, 1, 0)
      .convertTo(expected, CV_64F, 1.0 / (clean.saturation_level() - 512),
                 -512.0 / (clean.saturation_level() - 512));
  noisy.expose(shading, 1, 0)
      .convertTo(sim_frame, CV_64F, 1.0 / (noisy.saturation_level() - 512),
                 -512.0 / (noisy.saturation_level() - 512));
  const double sim_rms = cv::norm(sim_frame - expected) / std::sqrt(expected.total());
  ASSERT_GT(cv::mean(expected)[0], 0.1);  // a lit frame, not a dark one
  for (const cv::Mat& plane : half_size(raw)) {
    const double rms = cv::norm(plane - expected) / std::sqrt(expected.total());
    EXPECT_LT(rms, 1.5 * sim_rms + 1e-4);  // R and B: one site's noise, as the sim: pixel; G: less
    EXPECT_NEAR(cv::mean(plane)[0], cv::mean(expected)[0], 3 * sim_rms / std::sqrt(expected.total()) + 1e-4);
  }

  // EXIF: the exposure's start on the realtime clock, SubSec truncated to ms.
  const std::int64_t after_edge = exif_time_ns(path) - edge_realtime_ns;
  EXPECT_GE(after_edge, options_.lag_min_ns - kMs);
  EXPECT_LE(after_edge, options_.lag_max_ns + kMs);
  auto image = Exiv2::ImageFactory::open(path.string());
  image->readMetadata();
  const auto& exif = image->exifData();
  EXPECT_EQ(exif.findKey(Exiv2::ExifKey("Exif.Image.Make"))->toString(), "Lightstage");
  EXPECT_EQ(exif.findKey(Exiv2::ExifKey("Exif.Image.Model"))->toString(), "Simulated DSLR");
  EXPECT_NEAR(exif.findKey(Exiv2::ExifKey("Exif.Photo.ExposureTime"))->toFloat(),
              rig_.camera.exposure_us / 1e6, 1e-9);
  EXPECT_EQ(exif.findKey(Exiv2::ExifKey("Exif.Photo.ISOSpeedRatings"))->toLong(), 100);
  EXPECT_NEAR(exif.findKey(Exiv2::ExifKey("Exif.Photo.FNumber"))->toFloat(), 8, 1e-6);
}

TEST_F(DslrTest, TheCameraClockErrorShiftsTheExifTime) {
  options_.clock_offset_ns = -2500 * kMs;
  start();
  const std::int64_t t = monotonic_now_ns();
  const std::int64_t edge_realtime_ns =
      camera::convert_timestamp_ns(t, camera::ClockDomain::kMonotonic, camera::ClockDomain::kRealtime);
  feed(shutter(t));
  feed({led(t + 40 * kMs, 1, 0)});
  ASSERT_EQ(settle().written, 1u);
  const std::int64_t after_edge = exif_time_ns(dir_ / "IMG_0001.DNG") - edge_realtime_ns;
  EXPECT_GE(after_edge, -2500 * kMs + options_.lag_min_ns - kMs);
  EXPECT_LE(after_edge, -2500 * kMs + options_.lag_max_ns + kMs);
}

TEST_F(DslrTest, ColourScenesGiveEachSiteItsChannel) {
  scene_.colour = "0.9,0.6,0.3";
  scene_.sensor.noise = NoiseModel::kNone;
  start();
  const std::int64_t t = monotonic_now_ns() - 1000 * kMs;  // in the past: no waiting
  feed({led(t - 10 * kMs, 1, 1), led(t + 40 * kMs, 1, 0)});
  feed(shutter(t));
  ASSERT_EQ(settle().written, 1u);
  const Sensor sensor(scene_.sensor, rig_.camera);
  const cv::Mat frame =
      sensor.expose(world_->renderer().render_colour({{rig_.leds[0].position_mm, 1.0}}), 1, 0);
  std::vector<cv::Mat> bgr;
  cv::split(frame, bgr);
  const auto rgb = half_size(read_raw(dir_ / "IMG_0001.DNG"));
  const double scale = sensor.saturation_level() - 512;
  for (int c = 0; c < 3; ++c) {
    cv::Mat expected;
    bgr[static_cast<std::size_t>(2 - c)].convertTo(expected, CV_64F, 1.0 / scale, -512.0 / scale);
    // Offsets of 2..6 DN in the per-site white − black: at most 1e-4 of full scale.
    EXPECT_LT(cv::norm(rgb[static_cast<std::size_t>(c)] - expected, cv::NORM_INF), 2e-4) << "channel " << c;
  }
  EXPECT_GT(cv::mean(rgb[0])[0], 1.2 * cv::mean(rgb[1])[0]);  // the tint: red above green above blue
  EXPECT_GT(cv::mean(rgb[1])[0], 1.2 * cv::mean(rgb[2])[0]);
}

TEST_F(DslrTest, AnLedLitForPartOfTheWindowGivesItsShare) {
  scene_.sensor.noise = NoiseModel::kNone;
  options_.lag_min_ns = options_.lag_max_ns = 10 * kMs;  // window [t + 10 ms, t + 20 ms]
  start();
  const std::int64_t t = monotonic_now_ns() - 1000 * kMs;
  feed({led(t, 1, 1), led(t + 30 * kMs, 1, 0)});  // shot 1: the whole window
  feed(shutter(t));
  const std::int64_t t2 = t + 100 * kMs;
  feed({led(t2 + 17'500'000, 1, 1), led(t2 + 30 * kMs, 1, 0)});  // shot 2: the last quarter
  feed(shutter(t2));
  feed({led(t2 + 200 * kMs, 2, 0)});
  ASSERT_EQ(settle().written, 2u);
  const auto full = half_size(read_raw(dir_ / "IMG_0001.DNG"));
  const auto part = half_size(read_raw(dir_ / "IMG_0002.DNG"));
  for (std::size_t c = 0; c < 3; ++c) {
    ASSERT_GT(cv::mean(full[c])[0], 0.1);
    EXPECT_LT(cv::norm(part[c] - 0.25 * full[c], cv::NORM_INF), 1e-4) << "channel " << c;
  }
}

TEST_F(DslrTest, SaturatedSitesReadExactlyTheWhiteLevel) {
  options_.exposure_us = 200'000;           // 20x the rig's: the lit sphere clips
  for (const double iso : {100.0, 50.0}) {  // at ISO 50 the well fills below the top code
    options_.iso = iso;
    fs::remove_all(dir_);
    const SimulatedDslr& dslr = start();
    const std::int64_t t = monotonic_now_ns() - 1000 * kMs;
    feed({led(t, 1, 1), led(t + 300 * kMs, 1, 0)});
    feed(shutter(t));
    ASSERT_EQ(settle().written, 1u);
    const RawFile raw = read_raw(dir_ / "IMG_0001.DNG");
    EXPECT_EQ(raw.white, dslr.white_level());
    if (iso == 100) {
      EXPECT_EQ(raw.white, 65535);
    } else {
      EXPECT_LT(raw.white, 65535);
    }
    double highest = 0;
    cv::minMaxLoc(raw.mosaic, nullptr, &highest);
    EXPECT_EQ(highest, raw.white);
    // The brightest block clips at all four sites, whatever their black offsets.
    const cv::Mat centre = raw.mosaic(cv::Rect(30, 30, 2, 2));
    EXPECT_EQ(cv::countNonZero(centre == raw.white), 4) << "ISO " << iso << ": " << centre;
    dslr_.reset();
  }
}

TEST_F(DslrTest, FilesArriveInPressOrderWhateverTheirDelays) {
  options_.exposure_us = 2000;
  options_.lag_min_ns = 1 * kMs;
  options_.lag_max_ns = 3 * kMs;
  options_.delay_min_ns = 1 * kMs;
  options_.delay_max_ns = 100 * kMs;  // far wider than the 10 ms between presses
  start();
  const std::int64_t t = monotonic_now_ns();
  constexpr int kPresses = 12;
  for (int i = 0; i < kPresses; ++i) feed(shutter(t + i * 10 * kMs));
  feed({led(t + kPresses * 10 * kMs, 2, 0)});
  // Every look at the card sees IMG_0001 .. IMG_000k, never a gap.
  std::size_t seen = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(4);
  while (seen < kPresses && std::chrono::steady_clock::now() < deadline) {
    const auto names = files();
    std::set<std::string> prefix;
    for (std::size_t n = 1; n <= names.size(); ++n) prefix.insert(SimulatedDslr::file_name(n));
    ASSERT_EQ(names, prefix);
    seen = names.size();
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  EXPECT_EQ(seen, static_cast<std::size_t>(kPresses));
  for (int n = 2; n <= kPresses; ++n) {
    EXPECT_LE(fs::last_write_time(dir_ / SimulatedDslr::file_name(n - 1)),
              fs::last_write_time(dir_ / SimulatedDslr::file_name(n)));
    EXPECT_LT(exif_time_ns(dir_ / SimulatedDslr::file_name(n - 1)),
              exif_time_ns(dir_ / SimulatedDslr::file_name(n)));
  }
}

TEST_F(DslrTest, APressWhileBusyIsIgnored) {
  start();  // lag 5..15 ms, exposure 10 ms: busy for at least 15 ms after a press
  const std::int64_t t = monotonic_now_ns() - 1000 * kMs;
  feed(shutter(t));
  feed(shutter(t + 12 * kMs));  // during the first shot's lag or exposure
  feed(shutter(t + 50 * kMs));
  feed({led(t + 200 * kMs, 1, 0)});
  const DslrStats stats = settle();
  EXPECT_EQ(stats.presses, 3u);
  EXPECT_EQ(stats.ignored_busy, 1u);
  EXPECT_EQ(stats.taken, 2u);
  EXPECT_EQ(files(), (std::set<std::string>{"IMG_0001.DNG", "IMG_0002.DNG"}));
}

TEST_F(DslrTest, APressWithTheBufferFullIsIgnored) {
  options_.buffer_shots = 2;
  options_.delay_min_ns = options_.delay_max_ns = 200 * kMs;
  start();
  const std::int64_t t = monotonic_now_ns() - 2000 * kMs;
  for (int i = 0; i < 4; ++i) feed(shutter(t + i * 30 * kMs));  // 3rd and 4th: two shots still buffered
  feed(shutter(t + 400 * kMs));                                 // the buffer has emptied
  feed({led(t + 600 * kMs, 1, 0)});
  const DslrStats stats = settle();
  EXPECT_EQ(stats.ignored_buffer, 2u);
  EXPECT_EQ(stats.taken, 3u);
  EXPECT_EQ(files(), (std::set<std::string>{"IMG_0001.DNG", "IMG_0002.DNG", "IMG_0003.DNG"}));
}

TEST_F(DslrTest, ListedShotsAreDroppedKeepingTheirNumbers) {
  options_.drop_shots = {2, 4};
  start();
  const std::int64_t t = monotonic_now_ns() - 1000 * kMs;
  for (int i = 0; i < 5; ++i) feed(shutter(t + i * 50 * kMs));
  feed({led(t + 400 * kMs, 1, 0)});
  const DslrStats stats = settle();
  EXPECT_EQ(stats.taken, 5u);
  EXPECT_EQ(stats.dropped, 2u);
  EXPECT_EQ(files(), (std::set<std::string>{"IMG_0001.DNG", "IMG_0003.DNG", "IMG_0005.DNG"}));
}

TEST_F(DslrTest, TheDropRateDropsAboutThatShareReproducibly) {
  options_.drop_rate = 0.25;
  options_.exposure_us = 1000;
  options_.lag_min_ns = 1 * kMs;
  options_.lag_max_ns = 2 * kMs;
  options_.delay_min_ns = options_.delay_max_ns = 1 * kMs;
  rig_ = testing::make_rig({{0, 0, 300}}, 8, 8, 12.8);  // many shots: keep each small
  constexpr int kPresses = 400;
  std::vector<std::set<std::string>> runs;
  for (int run = 0; run < 2; ++run) {
    fs::remove_all(dir_);
    start();
    const std::int64_t t = monotonic_now_ns() - 10'000 * kMs;
    for (int i = 0; i < kPresses; ++i) feed(shutter(t + i * 10 * kMs));
    feed({led(t + (kPresses + 1) * 10 * kMs, 1, 0)});
    const DslrStats stats = settle();
    EXPECT_EQ(stats.taken, static_cast<std::uint64_t>(kPresses));
    EXPECT_EQ(stats.written + stats.dropped, static_cast<std::uint64_t>(kPresses));
    EXPECT_NEAR(static_cast<double>(stats.dropped), 0.25 * kPresses, 30);  // ±3.5 binomial sd
    runs.push_back(files());
    dslr_.reset();
  }
  EXPECT_EQ(runs[0], runs[1]);  // the same seed drops the same shots
}

TEST_F(DslrTest, NumberingContinuesAfterTheFilesAlreadyThere) {
  std::ofstream(dir_ / "IMG_0003.DNG") << "earlier";
  std::ofstream(dir_ / "IMG_0007.DNG") << "earlier";
  std::ofstream(dir_ / "notes.txt") << "not a shot";
  SimulatedDslr& dslr = start();
  EXPECT_EQ(dslr.first_file_number(), 8u);
  const std::int64_t t = monotonic_now_ns() - 1000 * kMs;
  feed(shutter(t));
  feed(shutter(t + 50 * kMs));
  feed({led(t + 200 * kMs, 1, 0)});
  EXPECT_EQ(settle().written, 2u);
  EXPECT_EQ(files(), (std::set<std::string>{"IMG_0003.DNG", "IMG_0007.DNG", "IMG_0008.DNG", "IMG_0009.DNG",
                                            "notes.txt"}));
  std::ifstream earlier(dir_ / "IMG_0007.DNG");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(earlier), {}), "earlier");
}

TEST_F(DslrTest, WithAFocusLineAPressNeedsTheHalfPress) {
  options_.focus_line = "FOCUS";
  start();
  const std::int64_t t = monotonic_now_ns() - 1000 * kMs;
  feed(shutter(t));  // no half-press yet
  feed({{t + 90 * kMs, "FOCUS", 1, -1, ""}});
  feed(shutter(t + 100 * kMs));
  feed({{t + 100 * kMs + 100'000, "FOCUS", 0, -1, ""}});  // released with the shutter
  feed(shutter(t + 200 * kMs));                           // released again
  feed({led(t + 400 * kMs, 1, 0)});
  const DslrStats stats = settle();
  EXPECT_EQ(stats.presses, 3u);
  EXPECT_EQ(stats.ignored_focus, 2u);
  EXPECT_EQ(files(), std::set<std::string>{"IMG_0001.DNG"});
}

TEST_F(DslrTest, AFolderPathThatIsAFileIsRefused) {
  options_.folder = dir_ / "card";
  std::ofstream(options_.folder) << "a file";
  EXPECT_EQ(lightstage::testing::error_of([&] { start(); }),
            "dslr: " + options_.folder.string() + " is not a folder");
}

TEST_F(DslrTest, AMissingFolderIsCreated) {
  options_.folder = dir_ / "card" / "DCIM";
  start();
  EXPECT_TRUE(fs::is_directory(options_.folder));
}

TEST_F(DslrTest, BadOptionsNameTheFieldAndValue) {
  options_.lag_min_ns = 20 * kMs;
  EXPECT_THAT(lightstage::testing::error_of([&] { options_.check(); }),
              HasSubstr("shutter lag [20000000, 15000000] ns must have 0 <= min <= max"));
  options_ = DslrOptions{};
  options_.folder = dir_;
  options_.drop_rate = 1;
  EXPECT_THAT(lightstage::testing::error_of([&] { options_.check(); }),
              HasSubstr("drop_rate must be in [0, 1), got 1"));
  options_.drop_rate = 0;
  options_.drop_shots = {0};
  EXPECT_THAT(lightstage::testing::error_of([&] { options_.check(); }),
              HasSubstr("drop_shots counts from 1"));
  options_.drop_shots = {};
  options_.black_offsets = {0, 1.5, 0, 0};
  EXPECT_THAT(lightstage::testing::error_of([&] { options_.check(); }),
              HasSubstr("black offset 1.5 must be a whole number"));
}

}  // namespace
}  // namespace lightstage::sim
