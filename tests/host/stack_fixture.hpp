#pragma once
// A small but complete ImageStack for the stack I/O tests.

#include "lightstage/common/image_stack.hpp"

#include <opencv2/core.hpp>

#include <fmt/format.h>

namespace lightstage::testing {

inline ImageStack small_stack(int frames = 4, int type = CV_16UC3, int width = 9, int height = 6) {
  ImageStack stack;
  cv::RNG rng(42);
  for (int i = 0; i < frames; ++i) {
    Frame frame;
    frame.filename = fmt::format("img_{:02}.png", i);
    frame.image = cv::Mat(height, width, type);
    rng.fill(frame.image, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(type) == CV_8U ? 256 : 65536);
    const double a = 0.7 * i;
    frame.light_direction = Vec3(0.5 * std::cos(a), 0.5 * std::sin(a), 0.8).normalized();
    frame.light_intensity = Vec3(1.0 + 0.1 * i, 1.5, 2.0 - 0.05 * i);
    frame.led_id = 10 + i;
    if (i % 2 == 0) frame.led_position_mm = Vec3(100.0 * i, -50, 400);
    frame.exposure_us = 1000 + i;
    frame.gain = 2.0;
    frame.black_level = 64;
    frame.saturation_level = 60000;
    stack.frames.push_back(frame);
  }
  stack.mask = cv::Mat(height, width, CV_8UC1, cv::Scalar::all(0));
  stack.mask(cv::Rect(1, 1, width - 3, height - 2)).setTo(255);
  GroundTruth truth;
  truth.normals = cv::Mat(height, width, CV_32FC3, cv::Scalar::all(0));
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (stack.mask.at<std::uint8_t>(y, x) == 0) continue;
      const Vec3 n = Vec3(0.1 * x - 0.3, 0.2 - 0.05 * y, 1).normalized();
      truth.normals.at<cv::Vec3f>(y, x) =
          cv::Vec3f(static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z()));
    }
  }
  truth.depth = cv::Mat(height, width, CV_32FC1);
  rng.fill(truth.depth, cv::RNG::UNIFORM, 1000.0, 1500.0);
  stack.ground_truth = truth;
  return stack;
}

}  // namespace lightstage::testing
