#include "lightstage/host/reflectance/rti_stack_fit.hpp"

#include "lightstage/common/error.hpp"

#include <opencv2/core.hpp>

namespace lightstage {

std::array<cv::Mat, 3> linear_channels(const Frame& frame) {
  const int depth = frame.image.depth();
  const double full = depth == CV_16U ? 65535.0 : depth == CV_8U ? 255.0 : 1.0;
  cv::Mat f;
  frame.image.convertTo(f, CV_32F);
  std::vector<cv::Mat> planes;
  cv::split(f, planes);
  std::array<cv::Mat, 3> rgb;
  for (int c = 0; c < 3; ++c) {
    // OpenCV holds colour as BGR: channel c (r, g, b) is plane 2 - c.
    const cv::Mat& plane = planes.size() == 3 ? planes[2 - c] : planes[0];
    const double intensity = frame.light_intensity[c] > 0 ? frame.light_intensity[c] : 1.0;
    rgb[c] = (plane - frame.black_level) / (full * intensity);
  }
  return rgb;
}

io::RtiImage fit_rti_stack(const ImageStack& stack, RtiBasis basis) {
  if (stack.frames.empty()) fail("RTI fit: the stack has no frames");
  io::RtiImage image;
  image.basis = basis;
  image.width = stack.width();
  image.height = stack.height();
  const Eigen::Index n = static_cast<Eigen::Index>(image.width) * image.height;
  const auto m = static_cast<Eigen::Index>(stack.frames.size());
  std::array<Eigen::MatrixXf, 3> values;
  for (auto& v : values) v.resize(n, m);
  Eigen::MatrixX3d lights(m, 3);
  for (Eigen::Index j = 0; j < m; ++j) {
    const Frame& frame = stack.frames[static_cast<std::size_t>(j)];
    if (frame.image.cols != image.width || frame.image.rows != image.height)
      fail("RTI fit: {} is {}x{}, the stack is {}x{}", frame.filename, frame.image.cols, frame.image.rows,
           image.width, image.height);
    lights.row(j) = frame.light_direction.normalized().transpose();
    const auto rgb = linear_channels(frame);
    for (int c = 0; c < 3; ++c) {
      const cv::Mat plane = rgb[c].isContinuous() ? rgb[c] : rgb[c].clone();
      values[c].col(j) = Eigen::Map<const Eigen::VectorXf>(plane.ptr<float>(), n);
    }
  }
  for (int c = 0; c < 3; ++c) image.channels[c] = fit_rti(basis, values[c], lights);
  return image;
}

}  // namespace lightstage
