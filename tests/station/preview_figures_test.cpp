// The live view's figures: histogram, clipping, sharpness.
#include "lightstage/station/preview_figures.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace lightstage::station {
namespace {

TEST(PreviewFigures, TheHistogramCountsEveryPixelAndClippingIsTheShareAtFullScale) {
  cv::Mat frame(10, 20, CV_16UC1, cv::Scalar(0));
  frame.rowRange(0, 5).setTo(32768);  // half scale: bin 32 of 64
  frame.row(9).setTo(65535);          // 20 pixels clipped
  const nlohmann::json figures = preview_figures(frame);
  EXPECT_EQ(figures["width"], 20);
  EXPECT_EQ(figures["height"], 10);
  const auto histogram = figures["histogram"].get<std::vector<std::size_t>>();
  ASSERT_EQ(histogram.size(), 64u);
  EXPECT_EQ(histogram[0], 80u);
  EXPECT_EQ(histogram[32], 100u);
  EXPECT_EQ(histogram[63], 20u);
  EXPECT_DOUBLE_EQ(figures["clipped"].get<double>(), 0.1);
  // One code below full scale is not clipped.
  frame.row(9).setTo(65534);
  EXPECT_DOUBLE_EQ(preview_figures(frame)["clipped"].get<double>(), 0.0);
}

TEST(PreviewFigures, SharpnessFallsAsTheFrameBlurs) {
  cv::Mat frame(64, 64, CV_8UC3);
  cv::randu(frame, 0, 255);
  cv::Mat blurred;
  cv::GaussianBlur(frame, blurred, cv::Size(0, 0), 2.0);
  const double sharp = preview_figures(frame)["sharpness"].get<double>();
  const double soft = preview_figures(blurred)["sharpness"].get<double>();
  EXPECT_GT(sharp, 10 * soft) << sharp << " vs " << soft;
}

TEST(PreviewFigures, ThePictureIsAnEightBitPngOfTheFrame) {
  cv::Mat frame(8, 8, CV_32FC1, cv::Scalar(0.5f));
  const std::string png = encode_preview_png(frame);
  const cv::Mat decoded =
      cv::imdecode(std::vector<unsigned char>(png.begin(), png.end()), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(decoded.type(), CV_8UC1);
  EXPECT_NEAR(decoded.at<unsigned char>(3, 3), 128, 1);
}

}  // namespace
}  // namespace lightstage::station
