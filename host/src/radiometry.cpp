#include "lightstage/host/radiometry.hpp"

#include "lightstage/common/error.hpp"
#include "util/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lightstage {
namespace {

constexpr double kRed = 0.2989, kGreen = 0.5870, kBlue = 0.1140;

double full_scale(int depth) { return depth == CV_16U ? 65535.0 : depth == CV_8U ? 255.0 : 1.0; }

double default_saturation(int depth) {
  return depth == CV_16U ? 65535.0 : depth == CV_8U ? 255.0 : std::numeric_limits<double>::infinity();
}

template <typename T>
void convert_frame(const Frame& frame, const std::vector<cv::Point>& pixels, const RadiometryOptions& options,
                   Eigen::Index column, ObservationMatrix& values, FlagMatrix& saturated) {
  const cv::Mat& image = frame.image;
  const double scale = full_scale(image.depth());
  const double saturation =
      frame.saturation_level > 0 ? frame.saturation_level : default_saturation(image.depth());
  const double black = frame.black_level;
  const Vec3& intensity = frame.light_intensity;  // r, g, b
  const bool colour = image.channels() == 3;
  // Grey images: divide by the grey of the light.
  // The BT.601 weights sum to 0.9999: normalise so that a grey light of 1 divides by exactly 1.
  const double grey_intensity =
      (kRed * intensity.x() + kGreen * intensity.y() + kBlue * intensity.z()) / (kRed + kGreen + kBlue);
  for (std::size_t p = 0; p < pixels.size(); ++p) {
    const T* px = image.ptr<T>(pixels[p].y) + pixels[p].x * image.channels();
    double value = 0;
    bool clipped = false;
    if (colour) {
      // BGR in memory.
      const double b = static_cast<double>(px[0]), g = static_cast<double>(px[1]),
                   r = static_cast<double>(px[2]);
      clipped = b >= saturation || g >= saturation || r >= saturation;
      value = kRed * ((r - black) / scale / intensity.x()) + kGreen * ((g - black) / scale / intensity.y()) +
              kBlue * ((b - black) / scale / intensity.z());
    } else {
      const double v = static_cast<double>(px[0]);
      clipped = v >= saturation;
      value = (v - black) / scale / grey_intensity;
    }
    if (options.clamp_to_one) value = std::min(value, 1.0);
    const auto row = static_cast<Eigen::Index>(p);
    values(row, column) = static_cast<float>(value);
    saturated(row, column) = clipped;
  }
}

}  // namespace

void RadiometryOptions::check() const {
  if (threads < 0) fail("RadiometryOptions.threads: must be 0 (automatic) or positive, got {}", threads);
}

Observations make_observations(const ImageStack& stack, const RadiometryOptions& options) {
  options.check();
  if (stack.frames.empty()) fail("radiometry: the stack has no frames");
  const cv::Mat& first = stack.frames.front().image;
  if (first.empty()) fail("radiometry: frame 0 ({}) has no image", stack.frames.front().filename);
  const int depth = first.depth();
  if ((depth != CV_8U && depth != CV_16U && depth != CV_32F) ||
      (first.channels() != 1 && first.channels() != 3)) {
    fail("radiometry: frame 0 ({}): unsupported pixel type {}", stack.frames.front().filename, first.type());
  }
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    const Frame& frame = stack.frames[i];
    if (frame.image.size() != first.size() || frame.image.type() != first.type()) {
      fail("radiometry: frame {} ({}) differs in size or type from frame 0", i, frame.filename);
    }
    if (!(frame.light_intensity.array() > 0).all()) {
      fail("radiometry: frame {} ({}): light intensity must be positive", i, frame.filename);
    }
  }
  if (!stack.mask.empty() && (stack.mask.type() != CV_8UC1 || stack.mask.size() != first.size())) {
    fail("radiometry: mask must be CV_8UC1 of {}x{}, got type {} of {}x{}", first.cols, first.rows,
         stack.mask.type(), stack.mask.cols, stack.mask.rows);
  }

  Observations obs;
  obs.size = first.size();
  obs.mask = cv::Mat(first.size(), CV_8UC1, cv::Scalar::all(0));
  for (int y = 0; y < first.rows; ++y) {
    const auto* in = stack.mask.empty() ? nullptr : stack.mask.ptr<std::uint8_t>(y);
    auto* out = obs.mask.ptr<std::uint8_t>(y);
    for (int x = 0; x < first.cols; ++x) {
      if (in == nullptr || in[x] != 0) {
        obs.pixels.emplace_back(x, y);
        out[x] = 255;
      }
    }
  }
  const auto images = static_cast<Eigen::Index>(stack.frames.size());
  const auto rows = static_cast<Eigen::Index>(obs.pixels.size());
  obs.intensities.resize(rows, images);
  obs.saturated.resize(rows, images);
  obs.lights.resize(images, 3);
  for (Eigen::Index j = 0; j < images; ++j) {
    obs.lights.row(j) = stack.frames[static_cast<std::size_t>(j)].light_direction.normalized().transpose();
  }
  util::parallel_chunks(
      stack.frames.size(), options.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
        for (std::size_t j = begin; j < end; ++j) {
          const Frame& frame = stack.frames[j];
          const auto column = static_cast<Eigen::Index>(j);
          switch (depth) {
            case CV_8U:
              convert_frame<std::uint8_t>(frame, obs.pixels, options, column, obs.intensities, obs.saturated);
              break;
            case CV_16U:
              convert_frame<std::uint16_t>(frame, obs.pixels, options, column, obs.intensities,
                                           obs.saturated);
              break;
            default:
              convert_frame<float>(frame, obs.pixels, options, column, obs.intensities, obs.saturated);
              break;
          }
        }
      });
  return obs;
}

}  // namespace lightstage
