#include "stack_region.hpp"

#include <map>

namespace lightstage::pipeline {

ImageStack read_region_rows(io::StackBands& stack, const cv::Rect& region, int y0, int rows) {
  ImageStack band = stack.read_band(y0, rows);
  if (region.x == 0 && region.width == stack.size().width) return band;
  const cv::Range columns(region.x, region.x + region.width);
  const auto cut = [&](cv::Mat& map) {
    if (!map.empty()) map = map.colRange(columns).clone();
  };
  std::map<const uchar*, cv::Mat> darks;
  for (Frame& frame : band.frames) {
    cut(frame.image);
    if (frame.dark.empty()) continue;
    auto [it, added] = darks.try_emplace(frame.dark.data);
    if (added) it->second = frame.dark.colRange(columns).clone();
    frame.dark = it->second;
  }
  cut(band.mask);
  if (band.ground_truth) {
    cut(band.ground_truth->normals);
    cut(band.ground_truth->depth);
  }
  return band;
}

}  // namespace lightstage::pipeline
