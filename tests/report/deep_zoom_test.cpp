// Deep Zoom pyramids (report/deep_zoom.hpp): every tile of every level equals
// the picture halved level by level (computed here independently), cut with
// its overlap; the descriptor names the sizes; bad input and interrupted runs.
#include "lightstage/host/report/deep_zoom.hpp"

#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <random>
#include <vector>

namespace lightstage::report {
namespace {

namespace fs = std::filesystem;
using lightstage::testing::error_of;
using ::testing::HasSubstr;

// A BGRA picture of random colours (or smooth ones: JPEG is for photographs, not
// noise), transparent outside an ellipse (as the report's pictures are).
cv::Mat picture(cv::Size size, unsigned seed, bool smooth = false) {
  cv::Mat out(size, CV_8UC4, cv::Scalar::all(0));
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x) {
      const double u = (x + 0.5) / size.width - 0.5, v = (y + 0.5) / size.height - 0.5;
      if (u * u + v * v > 0.2) continue;
      if (smooth) {
        out.at<cv::Vec4b>(y, x) = cv::Vec4b(static_cast<std::uint8_t>(255 * (u + 0.5)),
                                            static_cast<std::uint8_t>(255 * (v + 0.5)), 128, 255);
        continue;
      }
      out.at<cv::Vec4b>(y, x) =
          cv::Vec4b(static_cast<std::uint8_t>(byte(random)), static_cast<std::uint8_t>(byte(random)),
                    static_cast<std::uint8_t>(byte(random)), 255);
    }
  return out;
}

// The level under `level`: each pixel the alpha-weighted mean of its 2×2 block, alpha the block's mean.
cv::Mat halved(const cv::Mat& level) {
  cv::Mat out((level.rows + 1) / 2, (level.cols + 1) / 2, CV_8UC4, cv::Scalar::all(0));
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) {
      double sum[3] = {0, 0, 0}, weight = 0;
      int pixels = 0;
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          if (2 * y + dy >= level.rows || 2 * x + dx >= level.cols) continue;
          const cv::Vec4b p = level.at<cv::Vec4b>(2 * y + dy, 2 * x + dx);
          ++pixels;
          weight += p[3];
          for (int c = 0; c < 3; ++c) sum[c] += p[3] * p[c];
        }
      if (weight == 0) continue;
      cv::Vec4b& q = out.at<cv::Vec4b>(y, x);
      for (int c = 0; c < 3; ++c) q[c] = static_cast<std::uint8_t>(std::lround(sum[c] / weight));
      q[3] = static_cast<std::uint8_t>(std::lround(weight / pixels));
    }
  return out;
}

std::string read_text(const fs::path& file) { return lightstage::testing::read_text(file); }

// Writes `image` in bands of `band_rows` and checks every tile of every level and the descriptor.
void expect_pyramid(const cv::Mat& image, const DeepZoomOptions& options, int band_rows) {
  const fs::path dir = lightstage::testing::scratch_dir();
  const fs::path descriptor = dir / "normal.dzi";
  DeepZoomSummary summary;
  {
    DeepZoomWriter writer(descriptor, image.size(), options);
    for (int y = 0; y < image.rows; y += band_rows)
      writer.add(image.rowRange(y, std::min(image.rows, y + band_rows)));
    summary = writer.finish();
  }
  const int levels = deep_zoom_levels(image.size());
  EXPECT_EQ(summary.levels, levels);
  EXPECT_EQ(summary.descriptor, descriptor);
  const std::string xml = read_text(descriptor);
  EXPECT_THAT(xml, HasSubstr(fmt::format("TileSize=\"{}\" Overlap=\"{}\" Format=\"{}\"", options.tile_size,
                                         options.overlap, options.format)));
  EXPECT_THAT(xml, HasSubstr(fmt::format("<Size Width=\"{}\" Height=\"{}\"/>", image.cols, image.rows)));
  EXPECT_THAT(xml, HasSubstr("xmlns=\"http://schemas.microsoft.com/deepzoom/2008\""));

  const int t = options.tile_size, o = options.overlap;
  std::size_t tiles = 0;
  cv::Mat level = image;
  for (int l = levels - 1; l >= 0; --l) {
    SCOPED_TRACE(fmt::format("level {} ({}x{})", l, level.cols, level.rows));
    const fs::path folder = dir / "normal_files" / std::to_string(l);
    const int columns = (level.cols + t - 1) / t, rows = (level.rows + t - 1) / t;
    EXPECT_EQ(std::distance(fs::directory_iterator(folder), fs::directory_iterator()), columns * rows);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < columns; ++c) {
        const int x0 = std::max(0, c * t - o), x1 = std::min(level.cols, (c + 1) * t + o);
        const int y0 = std::max(0, r * t - o), y1 = std::min(level.rows, (r + 1) * t + o);
        const cv::Mat tile = cv::imread((folder / fmt::format("{}_{}.{}", c, r, options.format)).string(),
                                        cv::IMREAD_UNCHANGED);
        ASSERT_EQ(tile.size(), cv::Size(x1 - x0, y1 - y0)) << c << "_" << r;
        const cv::Mat expected = level(cv::Rect(x0, y0, x1 - x0, y1 - y0));
        if (options.format == "png") {
          ASSERT_EQ(tile.type(), CV_8UC4);
          EXPECT_EQ(cv::norm(tile, expected, cv::NORM_INF), 0) << c << "_" << r;
        } else {
          ASSERT_EQ(tile.type(), CV_8UC3);
          cv::Mat over_black(expected.size(), CV_8UC3);
          for (int y = 0; y < expected.rows; ++y)
            for (int x = 0; x < expected.cols; ++x) {
              const cv::Vec4b p = expected.at<cv::Vec4b>(y, x);
              for (int k = 0; k < 3; ++k)
                over_black.at<cv::Vec3b>(y, x)[k] =
                    static_cast<std::uint8_t>(std::lround(p[k] * p[3] / 255.0));
            }
          // JPEG is lossy: close on average, not pixel for pixel; the ellipse's edge rings, most in
          // the few pixels of the smallest levels.
          const double mean_error =
              cv::norm(tile, over_black, cv::NORM_L1) / static_cast<double>(tile.total() * 3);
          EXPECT_LT(mean_error, tile.total() >= 1024 ? 5.0 : 16.0) << c << "_" << r;
        }
        ++tiles;
      }
    level = halved(level);
  }
  EXPECT_EQ(summary.tiles, tiles);
  EXPECT_EQ(level.size(), cv::Size(1, 1)) << "level 0 is one pixel";
  // Nothing beside the pyramid: no staging folder left.
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_THAT(names, ::testing::ElementsAre("normal.dzi", "normal_files"));
  EXPECT_TRUE(fs::exists(dir / "normal_files" / ".lightstage-pyramid"));
}

TEST(DeepZoom, LevelsHalveTheLongerSideDownToOnePixel) {
  EXPECT_EQ(deep_zoom_levels({1, 1}), 1);
  EXPECT_EQ(deep_zoom_levels({2, 1}), 2);
  EXPECT_EQ(deep_zoom_levels({3, 2}), 3);
  EXPECT_EQ(deep_zoom_levels({256, 17}), 9);
  EXPECT_EQ(deep_zoom_levels({257, 17}), 10);
  EXPECT_EQ(deep_zoom_levels({6000, 4000}), 14);  // ceil(log2 6000) = 13, plus level 0
}

TEST(DeepZoom, EveryTileOfEveryLevelIsThePictureHalvedWithItsOverlap) {
  expect_pyramid(picture({600, 300}, 1), DeepZoomOptions{}, 37);
}

TEST(DeepZoom, SmallTilesWideOverlapAndOneRowBands) {
  DeepZoomOptions options;
  options.tile_size = 16;
  options.overlap = 3;
  options.threads = 2;
  expect_pyramid(picture({37, 23}, 2), options, 1);
  expect_pyramid(picture({1, 1}, 3), options, 1);
  expect_pyramid(picture({5, 40}, 4), options, 40);
}

TEST(DeepZoom, JpegTilesAreThePictureOverBlack) {
  DeepZoomOptions options;
  options.format = "jpg";
  const cv::Mat image = picture({300, 280}, 5, /*smooth=*/true);
  expect_pyramid(image, options, 64);
  // Outside the ellipse (transparent) is black.
  ASSERT_EQ(image.at<cv::Vec4b>(0, 0)[3], 0);
  const fs::path top = lightstage::testing::scratch_dir() / "normal_files" /
                       std::to_string(deep_zoom_levels(image.size()) - 1) / "0_0.jpg";
  const cv::Mat tile = cv::imread(top.string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(tile.type(), CV_8UC3);
  EXPECT_LT(cv::norm(tile(cv::Rect(0, 0, 8, 8)), cv::NORM_INF), 8);
}

TEST(DeepZoom, ReplacesItsOwnPyramidButNoOtherFolder) {
  const fs::path dir = lightstage::testing::scratch_dir();
  const cv::Mat image = picture({40, 30}, 6);
  for (int run = 0; run < 2; ++run) {
    DeepZoomWriter writer(dir / "albedo.dzi", image.size());
    writer.add(image);
    writer.finish();
  }
  EXPECT_TRUE(fs::exists(dir / "albedo_files" / "6" / "0_0.png"));
  fs::create_directories(dir / "mine_files");
  EXPECT_THAT(error_of([&] { DeepZoomWriter(dir / "mine.dzi", image.size()); }),
              HasSubstr((dir / "mine_files").string() + ": exists and is not a pyramid lightstage wrote"));
  // Tiles whose descriptor never came (a run stopped between the renames) are still its own.
  fs::remove(dir / "albedo.dzi");
  DeepZoomWriter again(dir / "albedo.dzi", image.size());
  again.add(image);
  again.finish();
  EXPECT_TRUE(fs::exists(dir / "albedo.dzi"));
}

// The hidden folders of a run that was killed are swept by the next; other hidden folders are not.
TEST(DeepZoom, AKilledRunsFoldersAreSweptByTheNext) {
  const fs::path dir = lightstage::testing::scratch_dir();
  const cv::Mat image = picture({40, 30}, 8);
  {
    DeepZoomWriter writer(dir / "normal.dzi", image.size());
    writer.add(image);
    writer.finish();
  }
  // What a killed run leaves: a copy of the tiles under its staging and replaced names.
  for (const char* stale : {".normal_files.partial-999999", ".normal_files.old-999999"})
    fs::copy(dir / "normal_files", dir / stale, fs::copy_options::recursive);
  fs::create_directories(dir / ".normal_files.partial-1" / "notes");  // not a pyramid's
  DeepZoomWriter writer(dir / "normal.dzi", image.size());
  EXPECT_FALSE(fs::exists(dir / ".normal_files.partial-999999"));
  EXPECT_FALSE(fs::exists(dir / ".normal_files.old-999999"));
  EXPECT_TRUE(fs::exists(dir / ".normal_files.partial-1" / "notes"));
}

TEST(DeepZoom, AnInterruptedPyramidLeavesNothing) {
  const fs::path dir = lightstage::testing::scratch_dir();
  const cv::Mat image = picture({600, 600}, 7);
  {
    DeepZoomWriter writer(dir / "normal.dzi", image.size());
    writer.add(image.rowRange(0, 300));  // tiles of the first row written, then the run ends
  }
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(DeepZoom, BadInputIsNamed) {
  const fs::path dir = lightstage::testing::scratch_dir();
  EXPECT_THAT(error_of([&] { DeepZoomWriter(dir / "normal.png", {4, 4}); }), HasSubstr("ends in .dzi"));
  EXPECT_THAT(error_of([&] { DeepZoomWriter(dir / "normal.dzi", {0, 4}); }), HasSubstr("at least one pixel"));
  DeepZoomOptions options;
  options.overlap = 254;
  EXPECT_THAT(error_of([&] { options.check(); }), HasSubstr("DeepZoomOptions.overlap"));
  options = {};
  options.format = "gif";
  EXPECT_THAT(error_of([&] { options.check(); }), HasSubstr("DeepZoomOptions.format: png or jpg, got 'gif'"));
  DeepZoomWriter writer(dir / "normal.dzi", {4, 4});
  EXPECT_THAT(error_of([&] { writer.add(cv::Mat(2, 4, CV_8UC3)); }),
              HasSubstr("normal.dzi: rows 0-1 of type"));
  EXPECT_THAT(error_of([&] { writer.add(cv::Mat(5, 4, CV_8UC4)); }), HasSubstr("do not fit its 4x4"));
  writer.add(cv::Mat(2, 4, CV_8UC4, cv::Scalar::all(9)));
  EXPECT_THAT(error_of([&] { writer.finish(); }), HasSubstr("a picture of 4 rows was given 2"));
}

}  // namespace
}  // namespace lightstage::report
