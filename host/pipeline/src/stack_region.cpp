#include "stack_region.hpp"

#include <functional>
#include <map>

namespace lightstage::pipeline {
namespace {

// Every image of `stack`: each frame's image and dark frame, the mask, the ground truth's maps.
void for_each_image(ImageStack& stack, const std::function<void(cv::Mat&)>& visit) {
  for (Frame& frame : stack.frames) {
    visit(frame.image);
    visit(frame.dark);
  }
  visit(stack.mask);
  if (stack.ground_truth) {
    visit(stack.ground_truth->normals);
    visit(stack.ground_truth->depth);
  }
}

}  // namespace

ImageStack stack_area(const ImageStack& stack, const cv::Rect& area) {
  ImageStack out = stack;
  for_each_image(out, [&](cv::Mat& image) {
    if (!image.empty()) image = image(area);
  });
  return out;
}

ImageStack read_region_rows(io::StackBands& stack, const cv::Rect& region, int y0, int rows) {
  ImageStack band = stack.read_band(y0, rows);
  if (region.x == 0 && region.width == stack.size().width) return band;
  band = stack_area(band, cv::Rect(region.x, 0, region.width, rows));
  // The region's pixels alone, each dark frame copied once (the frames that share one share its copy).
  std::map<const uchar*, cv::Mat> copies;
  for_each_image(band, [&](cv::Mat& image) {
    if (image.empty()) return;
    auto [it, added] = copies.try_emplace(image.data);
    if (added) it->second = image.clone();
    image = it->second;
  });
  return band;
}

}  // namespace lightstage::pipeline
