#include "lightstage/host/report/deep_zoom.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/jpeg_image.hpp"
#include "report/overview.hpp"

#include <fmt/format.h>
#include <unistd.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <system_error>
#include <vector>

namespace lightstage::report {
namespace fs = std::filesystem;
namespace {

// In every tiles folder this writer makes, from its start: which folders are its own to replace or sweep.
constexpr const char* kOwnerMark = ".lightstage-pyramid";

bool written_here(const fs::path& folder) { return fs::exists(folder / kOwnerMark); }

// Staging and replaced folders that runs which did not end left beside `files` (another process id).
void sweep_stale(const fs::path& files) {
  const std::string stem = "." + files.filename().string() + ".";
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(files.parent_path(), error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(stem + "partial-", 0) != 0 && name.rfind(stem + "old-", 0) != 0) continue;
    if (entry.is_directory() && written_here(entry.path())) fs::remove_all(entry.path(), error);
  }
}

}  // namespace

void DeepZoomOptions::check() const {
  if (tile_size < 1 || tile_size > 8192)
    fail("DeepZoomOptions.tile_size: must be 1 to 8192 pixels, got {}", tile_size);
  if (overlap < 0 || overlap >= tile_size)
    fail("DeepZoomOptions.overlap: must be 0 to tile_size - 1 ({}), got {}", tile_size - 1, overlap);
  if (format != "png" && format != "jpg") fail("DeepZoomOptions.format: png or jpg, got '{}'", format);
  if (threads < 0) fail("DeepZoomOptions.threads: must be 0 (every core) or positive, got {}", threads);
}

int deep_zoom_levels(cv::Size size) {
  int levels = 1;
  for (long long side = std::max(size.width, size.height); side > 1; side = (side + 1) / 2) ++levels;
  return levels;
}

struct DeepZoomWriter::State {
  fs::path descriptor, files, staging;
  cv::Size size;
  DeepZoomOptions options;
  int levels = 0;
  cv::Mat held;  // rows [held_y0, held_y0 + held.rows) of the picture
  int held_y0 = 0;
  int next_tile_row = 0;
  std::unique_ptr<Overview> below;  // the level under the picture, gathered whole
  std::atomic<std::size_t> tiles{0}, bytes{0};
  bool finished = false;

  int tile_count(int length) const { return (length + options.tile_size - 1) / options.tile_size; }

  // Tile row `r` of `level`, cut from `image`, whose row 0 is the level's row `image_y0`.
  void write_tile_row(int level, const cv::Mat& image, int image_y0, cv::Size level_size, int r) {
    const int t = options.tile_size, o = options.overlap;
    const int y0 = std::max(0, r * t - o), y1 = std::min(level_size.height, (r + 1) * t + o);
    const fs::path folder = staging / std::to_string(level);
    fs::create_directories(folder);
    parallel_for(tile_count(level_size.width), options.threads, [&](int c) {
      const int x0 = std::max(0, c * t - o), x1 = std::min(level_size.width, (c + 1) * t + o);
      const cv::Mat tile = image(cv::Rect(x0, y0 - image_y0, x1 - x0, y1 - y0));
      const fs::path file = folder / fmt::format("{}_{}.{}", c, r, options.format);
      std::string encoded;
      if (options.format == "png") {
        encoded = io::encode_png(tile, file.string());
      } else {
        cv::Mat over_black;
        cv::cvtColor(tile, over_black, cv::COLOR_BGRA2BGR);
        for (int y = 0; y < tile.rows; ++y)
          for (int x = 0; x < tile.cols; ++x)
            over_black.at<cv::Vec3b>(y, x) *= tile.at<cv::Vec4b>(y, x)[3] / 255.0;
        encoded = io::encode_jpeg(over_black, 90, file.string());
      }
      std::ofstream out(file, std::ios::binary);
      out.write(encoded.data(), static_cast<std::streamsize>(encoded.size()));
      if (!out.flush()) fail("{}: cannot write the tile (disk full or not writable?)", file.string());
      ++tiles;
      bytes += encoded.size();
    });
  }

  void write_level(int level, const cv::Mat& image) {
    for (int r = 0; r < tile_count(image.rows); ++r) write_tile_row(level, image, 0, image.size(), r);
  }
};

DeepZoomWriter::DeepZoomWriter(const fs::path& descriptor, cv::Size size, DeepZoomOptions options)
    : state_(std::make_unique<State>()) {
  options.check();
  if (descriptor.extension() != ".dzi") fail("{}: a Deep Zoom descriptor ends in .dzi", descriptor.string());
  if (size.width < 1 || size.height < 1)
    fail("{}: a Deep Zoom image needs at least one pixel, got {}x{}", descriptor.string(), size.width,
         size.height);
  State& s = *state_;
  s.descriptor = descriptor;
  s.files = descriptor.parent_path() / (descriptor.stem().string() + "_files");
  // Only a pyramid this writer made (its mark inside) is replaced.
  if (fs::exists(s.files) && !written_here(s.files))
    fail("{}: exists and is not a pyramid lightstage wrote (no {} inside); remove it or write elsewhere",
         s.files.string(), kOwnerMark);
  sweep_stale(s.files);
  s.staging = s.files.parent_path() / fmt::format(".{}.partial-{}", s.files.filename().string(), ::getpid());
  fs::remove_all(s.staging);
  fs::create_directories(s.staging);
  std::ofstream(s.staging / kOwnerMark) << "Deep Zoom tiles of " << descriptor.filename().string() << "\n";
  s.size = size;
  s.options = std::move(options);
  s.levels = deep_zoom_levels(size);
  if (s.levels > 1) s.below = std::make_unique<Overview>(size, 2);
}

DeepZoomWriter::~DeepZoomWriter() {
  if (state_ && !state_->finished) {
    std::error_code ignored;
    fs::remove_all(state_->staging, ignored);
  }
}

void DeepZoomWriter::add(const cv::Mat& band) {
  State& s = *state_;
  const int top = s.held_y0 + s.held.rows;
  if (band.type() != CV_8UC4 || band.cols != s.size.width || top + band.rows > s.size.height)
    fail("{}: rows {}-{} of type {} do not fit its {}x{} BGRA picture", s.descriptor.string(), top,
         top + band.rows - 1, band.type(), s.size.width, s.size.height);
  if (s.below) s.below->add(band);
  if (s.held.empty())
    s.held = band.clone();
  else
    cv::vconcat(s.held, band, s.held);
  const int t = s.options.tile_size, o = s.options.overlap;
  const int available = s.held_y0 + s.held.rows;
  const int level = s.levels - 1;
  while (s.next_tile_row < s.tile_count(s.size.height) &&
         available >= std::min(s.size.height, (s.next_tile_row + 1) * t + o)) {
    s.write_tile_row(level, s.held, s.held_y0, s.size, s.next_tile_row);
    ++s.next_tile_row;
    // The next tile row starts `overlap` rows above its first own row.
    const int keep_from = std::max(s.held_y0, std::min(available, s.next_tile_row * t - o));
    s.held = s.held.rowRange(keep_from - s.held_y0, s.held.rows).clone();
    s.held_y0 = keep_from;
  }
}

DeepZoomSummary DeepZoomWriter::finish() {
  State& s = *state_;
  if (s.next_tile_row != s.tile_count(s.size.height))
    fail("{}: a picture of {} rows was given {}", s.descriptor.string(), s.size.height,
         s.held_y0 + s.held.rows);
  s.held.release();
  if (s.below) {
    cv::Mat level = s.below->finish();
    s.below.reset();
    for (int l = s.levels - 2; l >= 0; --l) {
      s.write_level(l, level);
      if (l == 0) break;
      Overview half(level.size(), 2);
      half.add(level);
      level = half.finish();
    }
  }
  const std::string xml = fmt::format(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<Image xmlns=\"http://schemas.microsoft.com/deepzoom/2008\" TileSize=\"{}\" Overlap=\"{}\" "
      "Format=\"{}\">\n  <Size Width=\"{}\" Height=\"{}\"/>\n</Image>\n",
      s.options.tile_size, s.options.overlap, s.options.format, s.size.width, s.size.height);
  const fs::path partial = s.descriptor.parent_path() / ("." + s.descriptor.filename().string() + ".partial");
  {
    std::ofstream out(partial, std::ios::binary);
    out << xml;
    if (!out.flush()) fail("{}: cannot write the descriptor", s.descriptor.string());
  }
  // Into place: the tiles, then the descriptor that names them; a step that fails puts the earlier pyramid
  // back.
  const fs::path old =
      s.files.parent_path() / fmt::format(".{}.old-{}", s.files.filename().string(), ::getpid());
  const bool replacing = fs::exists(s.files);
  if (replacing) fs::rename(s.files, old);
  try {
    fs::rename(s.staging, s.files);
    try {
      fs::rename(partial, s.descriptor);
    } catch (...) {
      fs::rename(s.files, s.staging);
      throw;
    }
  } catch (...) {
    std::error_code ignored;
    if (replacing) fs::rename(old, s.files, ignored);
    fs::remove(partial, ignored);
    throw;
  }
  std::error_code ignored;
  fs::remove_all(old, ignored);
  s.finished = true;
  DeepZoomSummary summary;
  summary.descriptor = s.descriptor;
  summary.size = s.size;
  summary.tile_size = s.options.tile_size;
  summary.overlap = s.options.overlap;
  summary.format = s.options.format;
  summary.levels = s.levels;
  summary.tiles = s.tiles;
  summary.bytes = s.bytes + xml.size();
  return summary;
}

}  // namespace lightstage::report
