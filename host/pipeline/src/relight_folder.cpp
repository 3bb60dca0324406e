#include "lightstage/pipeline/relight_folder.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/output_folder.hpp"
#include "lightstage/host/reflectance/relight.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>

namespace lightstage::pipeline {

nlohmann::json relight_folder(const RelightSettings& settings) {
  if (settings.lights.empty()) fail("relight: give at least one --light x,y,z or --turntable N");
  io::require_separate_output(settings.out, {settings.input});
  const RelightModel model = load_relight_model(settings.input);
  const bool colour = !model.chroma.empty() && !settings.grey;
  std::vector<cv::Mat> frames;
  std::vector<float> all;
  for (const auto& l : settings.lights) {
    frames.push_back(colour ? relight_colour(model, l) : relight(model, l));
    const cv::Mat& frame = frames.back();
    for (int y = 0; y < frame.rows; ++y) {
      if (model.solved.empty()) break;
      const float* row = frame.ptr<float>(y);
      for (int x = 0; x < frame.cols; ++x)
        if (model.solved.at<std::uint8_t>(y, x) != 0)
          all.insert(all.end(), row + x * frame.channels(), row + (x + 1) * frame.channels());
    }
  }
  // White: the 99.5th percentile of every channel of the object's pixels, so
  // that saturated colours keep their hue.
  double scale = settings.scale;
  if (!(scale > 0)) {
    scale = 1;
    if (!all.empty()) {
      const auto at = all.begin() + static_cast<std::ptrdiff_t>(0.995 * static_cast<double>(all.size() - 1));
      std::nth_element(all.begin(), at, all.end());
      if (*at > 0) scale = *at;
    }
  }
  std::filesystem::create_directories(settings.out);
  nlohmann::json summary = {{"input", settings.input.string()},
                            {"scale", scale},
                            {"model", model.order > 0 ? "bipolynomial" : "lambert"},
                            {"order", model.order},
                            {"colour", colour},
                            {"frames", nlohmann::json::array()}};
  for (std::size_t i = 0; i < frames.size(); ++i) {
    cv::Mat scaled = frames[i] / scale, image;
    cv::min(scaled, 1.0, scaled);
    scaled.convertTo(image, colour ? CV_16UC3 : CV_16UC1, 65535.0);
    const std::string name = fmt::format("relit_{:03d}.png", i);
    io::write_png16(settings.out / name, image);
    const Vec3 l = settings.lights[i].normalized();
    summary["frames"].push_back({{"file", name}, {"light", {l.x(), l.y(), l.z()}}});
  }
  std::ofstream json(settings.out / "relight.json");
  json << summary.dump(2) << "\n";
  if (!json) fail("{}: cannot write", (settings.out / "relight.json").string());
  return summary;
}

}  // namespace lightstage::pipeline
