#pragma once
// A Deep Zoom image (DZI) of a report picture given a band of rows at a time,
// so that a result too large for a page can be zoomed to its own pixels in a
// Deep Zoom viewer (OpenSeadragon and the like). NAME.dzi is the XML
// descriptor (TileSize, Overlap, Format, Size); NAME_files/L/C_R.FORMAT are
// the tiles of level L, column C and row R. Level 0 is one pixel, the last
// level (ceil(log2(max(W, H)))) the picture itself, each level the one above
// halved and rounded up, each pixel the alpha-weighted mean of a 2×2 block
// (overview.hpp). A tile is tile_size square, plus `overlap` pixels on each
// side that has a neighbour, cut at the level's edge.
//
// Memory: a strip of the picture (tile_size + 2·overlap rows) and the level
// below it whole (a quarter of the pixels); the levels under that are made
// from it at the end. Tiles go to a hidden folder beside the final one,
// renamed into place with the descriptor last, so an interrupted run leaves
// no half-written tiles under NAME_files; an earlier pyramid of the same name
// is replaced, and put back if that fails. A mark file inside each tiles
// folder says it is one this writer made: only those are replaced, and the
// hidden folders of runs that were killed are swept when the next one starts.

#include <opencv2/core.hpp>

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>

namespace lightstage::report {

struct DeepZoomOptions {
  int tile_size = 254;         // 254 + 2 × 1 = 256: the usual tiles
  int overlap = 1;             // ≥ 0, < tile_size
  std::string format = "png";  // png (with alpha) or jpg (over black, quality 90)
  int threads = 0;             // tiles of a row encoded side by side (0 = every core)

  void check() const;  // throws InputError naming the field and value
};

struct DeepZoomSummary {
  std::filesystem::path descriptor;  // NAME.dzi
  cv::Size size;
  int tile_size = 0, overlap = 0;
  std::string format;
  int levels = 0;  // 0 .. levels - 1
  std::size_t tiles = 0;
  std::size_t bytes = 0;  // the tiles' and the descriptor's
};

// The number of levels of a w × h Deep Zoom image: ceil(log2(max(w, h))) + 1.
int deep_zoom_levels(cv::Size size);

class DeepZoomWriter {
 public:
  // `descriptor` ends in .dzi; the tiles go to the folder of its stem + "_files".
  DeepZoomWriter(const std::filesystem::path& descriptor, cv::Size size, DeepZoomOptions options = {});
  ~DeepZoomWriter();  // without finish(): the partial tiles are removed
  DeepZoomWriter(const DeepZoomWriter&) = delete;
  DeepZoomWriter& operator=(const DeepZoomWriter&) = delete;

  // The next band.rows rows of the picture (CV_8UC4, BGRA, the picture's width).
  void add(const cv::Mat& band);
  // After every row: the remaining tiles, every lower level and the descriptor.
  DeepZoomSummary finish();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace lightstage::report
