#include "report/overview.hpp"

#include "lightstage/common/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace lightstage::report {

int overview_factor(cv::Size size, int max_pixels) {
  const double pixels = static_cast<double>(size.width) * size.height;
  int factor = std::max(1, static_cast<int>(std::ceil(std::sqrt(pixels / std::max(max_pixels, 1)))));
  // The square root can round under: ceil of each side is what must fit.
  while (static_cast<double>((size.width + factor - 1) / factor) * ((size.height + factor - 1) / factor) >
         max_pixels)
    ++factor;
  return factor;
}

Overview::Overview(cv::Size size, int factor, Blocks blocks)
    : size_(size), factor_(std::max(factor, 1)), blocks_(blocks) {}

void Overview::add(const cv::Mat& band) {
  const bool type_ok = blocks_ == Blocks::kMean ? band.type() == CV_8UC4 : band.depth() == CV_8U;
  if (!type_ok || band.cols != size_.width || rows_added_ + band.rows > size_.height)
    fail("report: picture rows {}-{} do not fit its {}x{} picture", rows_added_, rows_added_ + band.rows - 1,
         size_.width, size_.height);
  if (out_.empty()) {
    // Made with the first rows: a picture the result does not have takes nothing.
    const int width = (size_.width + factor_ - 1) / factor_;
    out_ = cv::Mat((size_.height + factor_ - 1) / factor_, width, band.type(), cv::Scalar::all(0));
    sums_.assign(static_cast<std::size_t>(width) * 4, 0.0);
    block_pixels_.assign(static_cast<std::size_t>(width), 0);
  }
  if (factor_ == 1) {
    band.copyTo(out_.rowRange(rows_added_, rows_added_ + band.rows));
    rows_added_ += band.rows;
    return;
  }
  if (blocks_ == Blocks::kFirstPixel) {
    for (int r = 0; r < band.rows; ++r, ++rows_added_) {
      if (rows_added_ % factor_ != 0) continue;
      auto* out = out_.ptr(rows_added_ / factor_);
      for (int x = 0; x < out_.cols; ++x)
        std::memcpy(out + x * band.elemSize(), band.ptr(r, x * factor_), band.elemSize());
    }
    return;
  }
  for (int r = 0; r < band.rows; ++r) {
    const auto* row = band.ptr<cv::Vec4b>(r);
    for (int x = 0; x < band.cols; ++x) {
      const auto i = static_cast<std::size_t>(x / factor_);
      ++block_pixels_[i];
      // Weighted by alpha: a picture's own pixels are 0 or 255, an overview's (a pyramid's
      // lower levels, deep_zoom.hpp) the share of pixels they stand for.
      const double alpha = row[x][3];
      if (alpha == 0) continue;
      for (int c = 0; c < 3; ++c) sums_[4 * i + static_cast<std::size_t>(c)] += alpha * row[x][c];
      sums_[4 * i + 3] += alpha;
    }
    ++rows_added_;
    if (rows_added_ % factor_ == 0 || rows_added_ == size_.height) emit_row();
  }
}

void Overview::emit_row() {
  auto* row = out_.ptr<cv::Vec4b>((rows_added_ - 1) / factor_);
  for (int x = 0; x < out_.cols; ++x) {
    const auto i = static_cast<std::size_t>(x);
    const double weight = sums_[4 * i + 3];
    if (weight > 0) {
      for (int c = 0; c < 3; ++c)
        row[x][c] =
            cv::saturate_cast<std::uint8_t>(std::lround(sums_[4 * i + static_cast<std::size_t>(c)] / weight));
      row[x][3] = cv::saturate_cast<std::uint8_t>(std::lround(weight / block_pixels_[i]));
    }
  }
  std::fill(sums_.begin(), sums_.end(), 0.0);
  std::fill(block_pixels_.begin(), block_pixels_.end(), 0);
}

cv::Mat Overview::finish() {
  if (rows_added_ != size_.height)
    fail("report: a picture of {} rows was given {}", size_.height, rows_added_);
  return out_;
}

}  // namespace lightstage::report
