#include "lightstage/host/calibration/calibration_images.hpp"

#include "io/stack_manifest.hpp"
#include "io/text_table.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/image_stack.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/mask.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <limits>

namespace lightstage::calibration {
namespace {

namespace fs = std::filesystem;

constexpr double kRed = 0.2989, kGreen = 0.5870, kBlue = 0.1140;

double full_scale(int depth) { return depth == CV_16U ? 65535.0 : depth == CV_8U ? 255.0 : 1.0; }

// Grey values and saturation flags of one frame.
void convert(const Frame& frame, cv::Mat* grey, cv::Mat* saturated) {
  cv::Mat image;
  frame.image.convertTo(image, CV_MAKETYPE(CV_64F, frame.image.channels()));
  const double scale = full_scale(frame.image.depth());
  const double level = frame.saturation_level > 0      ? frame.saturation_level
                       : frame.image.depth() == CV_32F ? std::numeric_limits<double>::infinity()
                                                       : scale;
  *grey = cv::Mat(image.size(), CV_32FC1);
  *saturated = cv::Mat(image.size(), CV_8UC1, cv::Scalar::all(0));
  const int channels = image.channels();
  for (int r = 0; r < image.rows; ++r) {
    const auto* in = image.ptr<double>(r);
    auto* out = grey->ptr<float>(r);
    auto* flag = saturated->ptr<std::uint8_t>(r);
    for (int c = 0; c < image.cols; ++c) {
      const double* px = in + c * channels;
      double value = 0;
      bool clipped = false;
      if (channels == 3) {  // BGR in memory
        value = kBlue * px[0] + kGreen * px[1] + kRed * px[2];
        clipped = px[0] >= level || px[1] >= level || px[2] >= level;
      } else {
        value = px[0];
        clipped = px[0] >= level;
      }
      out[c] = static_cast<float>((value - frame.black_level) / scale);
      flag[c] = clipped ? 255 : 0;
    }
  }
}

}  // namespace

std::optional<CameraGeometry> camera_from_manifest(const fs::path& path) {
  std::ifstream in(path);
  nlohmann::json manifest;
  try {
    manifest = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    fail("{}: not valid JSON: {}", path.string(), e.what());
  }
  if (!manifest.is_object()) return std::nullopt;
  if (const auto camera = manifest.find("camera"); camera != manifest.end())
    return CameraGeometry::from_json(*camera, path.string() + ": camera");
  if (const auto sim = manifest.find("simulation"); sim != manifest.end() && sim->is_object()) {
    if (const auto camera = sim->find("camera"); camera != sim->end())
      return CameraGeometry::from_json(*camera, path.string() + ": simulation.camera");
  }
  return std::nullopt;
}

CalibrationImages load_calibration_images(const fs::path& folder, int min_images, int threads) {
  std::error_code error;
  if (!fs::is_directory(folder, error)) fail("{}: no such stack folder", folder.string());
  const fs::path names_path = folder / "filenames.txt";
  const auto names = io::read_text_lines(names_path);
  for (const auto& name : names) {
    const fs::path relative(name.text);
    if (relative.is_absolute() ||
        std::any_of(relative.begin(), relative.end(), [](const fs::path& part) { return part == ".."; })) {
      fail("{}:{}: '{}' must name a file inside the stack folder", names_path.string(), name.number,
           name.text);
    }
  }
  if (names.empty() || static_cast<int>(names.size()) < min_images) {
    fail("{}: {} image(s) listed, at least {} needed", names_path.string(), names.size(),
         std::max(min_images, 1));
  }
  ImageStack stack;
  stack.frames.resize(names.size());
  for (std::size_t i = 0; i < names.size(); ++i) stack.frames[i].filename = names[i].text;
  parallel_chunks(names.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      stack.frames[i].image = io::read_image(folder / stack.frames[i].filename);
  });
  const cv::Mat& first = stack.frames.front().image;
  for (const auto& frame : stack.frames) {
    if (frame.image.size() != first.size() || frame.image.type() != first.type()) {
      fail("{}: image is {}x{} of type {}, but {} is {}x{} of type {}", (folder / frame.filename).string(),
           frame.image.cols, frame.image.rows, frame.image.type(), stack.frames.front().filename, first.cols,
           first.rows, first.type());
    }
  }
  CalibrationImages images;
  images.folder = folder;
  const fs::path manifest_path = folder / "manifest.json";
  if (fs::exists(manifest_path, error)) {
    io::apply_manifest(manifest_path, stack);
    images.camera = camera_from_manifest(manifest_path);
    if (images.camera && (images.camera->width != first.cols || images.camera->height != first.rows)) {
      fail("{}: the camera is {}x{}, the images are {}x{}", manifest_path.string(), images.camera->width,
           images.camera->height, first.cols, first.rows);
    }
  }
  const fs::path mask_path = folder / "mask.png";
  if (fs::exists(mask_path, error)) {
    images.mask = io::read_mask(mask_path);
    if (images.mask.size() != first.size()) {
      fail("{}: mask is {}x{}, images are {}x{}", mask_path.string(), images.mask.cols, images.mask.rows,
           first.cols, first.rows);
    }
  }
  images.filenames.resize(names.size());
  images.led_ids.resize(names.size());
  images.grey.resize(names.size());
  images.saturated.resize(names.size());
  parallel_chunks(names.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      convert(stack.frames[i], &images.grey[i], &images.saturated[i]);
      images.filenames[i] = stack.frames[i].filename;
      images.led_ids[i] = stack.frames[i].led_id;
      stack.frames[i].image.release();
    }
  });
  return images;
}

cv::Mat median_image(const std::vector<cv::Mat>& images) {
  if (images.empty()) fail("median_image: no images");
  const cv::Size size = images.front().size();
  cv::Mat median(size, CV_32FC1);
  const std::size_t n = images.size();
  parallel_chunks(static_cast<std::size_t>(size.height), 0,
                  [&](std::size_t, std::size_t begin, std::size_t end) {
                    std::vector<float> values(n);
                    for (std::size_t r = begin; r < end; ++r) {
                      const int row = static_cast<int>(r);
                      for (int c = 0; c < size.width; ++c) {
                        for (std::size_t i = 0; i < n; ++i) values[i] = images[i].at<float>(row, c);
                        const auto middle = values.begin() + static_cast<std::ptrdiff_t>(n / 2);
                        std::nth_element(values.begin(), middle, values.end());
                        median.at<float>(row, c) = *middle;
                      }
                    }
                  });
  return median;
}

cv::Mat max_image(const std::vector<cv::Mat>& images) {
  if (images.empty()) fail("max_image: no images");
  cv::Mat result = images.front().clone();
  for (std::size_t i = 1; i < images.size(); ++i) result = cv::max(result, images[i]);
  return result;
}

}  // namespace lightstage::calibration
