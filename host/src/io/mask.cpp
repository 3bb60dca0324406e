#include "lightstage/host/io/mask.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/image_io.hpp"

#include <vector>

namespace lightstage::io {

cv::Mat read_mask(const std::filesystem::path& path) {
  const cv::Mat raw = read_image(path);
  cv::Mat grey = raw;
  if (raw.channels() == 3) {
    std::vector<cv::Mat> channels;
    cv::split(raw, channels);
    grey = cv::max(cv::max(channels[0], channels[1]), channels[2]);
  }
  double max_value = 0;
  cv::minMaxLoc(grey, nullptr, &max_value);
  if (!(max_value > 0)) fail("{}: mask is empty (all pixels are 0)", path.string());
  cv::Mat mask;
  cv::compare(grey, max_value, mask, cv::CMP_EQ);  // 255 where equal
  return mask;
}

}  // namespace lightstage::io
