#include "lightstage/station/preview_figures.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/image_io.hpp"

#include <opencv2/imgproc.hpp>

#include <vector>

namespace lightstage::station {
namespace {

// Full scale of a frame's type: 8 and 16 bits their maximum, float frames 1.
double full_scale(const cv::Mat& frame) {
  switch (frame.depth()) {
    case CV_8U:
      return 255.0;
    case CV_16U:
      return 65535.0;
    case CV_32F:
    case CV_64F:
      return 1.0;
    default:
      throw Error("preview: the camera gave a frame of an unexpected pixel type");
  }
}

// Grey, in shares of full scale.
cv::Mat grey_share(const cv::Mat& frame) {
  cv::Mat grey;
  if (frame.channels() == 3)
    cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
  else
    grey = frame;
  cv::Mat share;
  grey.convertTo(share, CV_32F, 1.0 / full_scale(frame));
  return share;
}

}  // namespace

std::string encode_preview_png(const cv::Mat& frame) {
  cv::Mat eight;
  frame.convertTo(eight, CV_8U, 255.0 / full_scale(frame));
  return io::encode_png(eight, "preview");
}

nlohmann::json preview_figures(const cv::Mat& frame) {
  const cv::Mat share = grey_share(frame);
  constexpr int kBins = 64;
  std::vector<std::size_t> histogram(kBins, 0);
  std::size_t clipped = 0;
  double sum = 0;
  // A pixel within half a code of full scale is clipped (for float frames: at or above 1).
  const double clip_at =
      frame.depth() == CV_32F || frame.depth() == CV_64F ? 1.0 : 1.0 - 0.5 / full_scale(frame);
  for (int r = 0; r < share.rows; ++r) {
    const float* row = share.ptr<float>(r);
    for (int c = 0; c < share.cols; ++c) {
      const double v = row[c];
      sum += v;
      if (v >= clip_at) ++clipped;
      const int bin = static_cast<int>(std::clamp(v, 0.0, 1.0) * kBins);
      ++histogram[static_cast<std::size_t>(std::min(bin, kBins - 1))];
    }
  }
  cv::Mat laplacian;
  cv::Laplacian(share, laplacian, CV_32F);
  cv::Scalar mean, deviation;
  cv::meanStdDev(laplacian, mean, deviation);
  const double pixels = static_cast<double>(share.total());
  return {{"width", frame.cols},
          {"height", frame.rows},
          {"histogram", histogram},
          {"clipped", pixels > 0 ? static_cast<double>(clipped) / pixels : 0.0},
          {"mean", pixels > 0 ? sum / pixels : 0.0},
          {"sharpness", deviation[0] * deviation[0] * 1e4}};
}

}  // namespace lightstage::station
