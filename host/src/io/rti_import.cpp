#include "lightstage/host/io/rti_import.hpp"

#include "lightstage/common/error.hpp"

#include <cmath>
#include <vector>

namespace lightstage::io {

std::string rti_image_name(const std::string& lp_filename, const std::string& source) {
  const std::size_t cut = lp_filename.find_last_of("/\\");
  const std::string name = cut == std::string::npos ? lp_filename : lp_filename.substr(cut + 1);
  if (name.empty() || name == "." || name == "..")
    fail("{}: image name: '{}' names no file", source, lp_filename.substr(0, 200));
  for (const unsigned char c : name)
    if (c < 0x20 || c == 0x7f)
      fail("{}: image name: '{}' holds a control character", source, lp_filename.substr(0, 200));
  return name;
}

double srgb_to_linear(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

cv::Mat linear_frame(const cv::Mat& image, const std::optional<InverseResponse>& response,
                     const std::string& source) {
  if (image.depth() == CV_16U) return image;
  if (image.depth() != CV_8U)
    fail("{}: pixel type: only 8-bit (sRGB or --response) and 16-bit (linear) images are read", source);
  if (response && response->bits() != 8)
    fail("{}: --response: the response is for {}-bit data, the image is 8-bit", source, response->bits());
  cv::Mat lut(1, 256, CV_16U);
  for (int dn = 0; dn < 256; ++dn) {
    const double lin = response ? response->at(dn) : srgb_to_linear(dn / 255.0);
    lut.at<std::uint16_t>(0, dn) =
        static_cast<std::uint16_t>(std::lround(std::clamp(lin, 0.0, 1.0) * 65535.0));
  }
  std::vector<cv::Mat> planes;
  cv::split(image, planes);
  for (auto& p : planes) {
    cv::Mat out(p.size(), CV_16U);
    for (int y = 0; y < p.rows; ++y) {
      const auto* in = p.ptr<std::uint8_t>(y);
      auto* o = out.ptr<std::uint16_t>(y);
      for (int x = 0; x < p.cols; ++x) o[x] = lut.at<std::uint16_t>(0, in[x]);
    }
    p = out;
  }
  cv::Mat merged;
  cv::merge(planes, merged);
  return merged;
}

}  // namespace lightstage::io
