#pragma once
// A picture of the report (BGRA, maps.hpp) gathered a band of rows at a time
// into its overview: the picture itself when it fits the page's pixel budget,
// else each factor × factor block of it averaged into one pixel (its colours
// weighted by alpha, alpha the block's mean: over a picture's opaque pixels,
// alpha their share of the block), so that a result
// larger than memory is drawn without holding its full-size pictures.

#include <opencv2/core.hpp>

#include <vector>

namespace lightstage::report {

// The smallest whole factor that brings `size` within `max_pixels` (≥ 1).
int overview_factor(cv::Size size, int max_pixels);

class Overview {
 public:
  // kMean: a block's mean (CV_8UC4 pictures); kFirstPixel: its first pixel,
  // for pictures of categories, whose mean would be a colour of none (any
  // 8-bit picture, its type kept).
  enum class Blocks { kMean, kFirstPixel };
  Overview(cv::Size size, int factor, Blocks blocks = Blocks::kMean);

  // The next band.rows rows of the picture (the picture's width).
  void add(const cv::Mat& band);
  // After every row: the overview, ceil(size / factor).
  cv::Mat finish();

  int factor() const { return factor_; }

 private:
  void emit_row();

  cv::Size size_;
  int factor_ = 1;
  Blocks blocks_ = Blocks::kMean;
  int rows_added_ = 0;
  cv::Mat out_;
  std::vector<double> sums_;       // per overview pixel of the row being gathered: b, g, r, opaque count
  std::vector<int> block_pixels_;  // pixels of each block so far
};

}  // namespace lightstage::report
