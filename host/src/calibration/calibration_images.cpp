#include "lightstage/host/calibration/calibration_images.hpp"

#include "io/stack_manifest.hpp"
#include "io/text_table.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/image_stack.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/mask.hpp"
#include "lightstage/host/io/row_reader.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <limits>
#include <memory>

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

CalibrationImages load_calibration_index(const fs::path& folder, int min_images) {
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
  CalibrationImages images;
  images.folder = folder;
  {
    const auto first = io::open_row_reader(folder / stack.frames.front().filename, io::RowReading::kOnce);
    images.image_size = first->size();
    images.image_type = first->type();
  }
  const cv::Size size = images.image_size;
  const fs::path manifest_path = folder / "manifest.json";
  if (fs::exists(manifest_path, error)) {
    io::apply_manifest(manifest_path, stack);
    images.camera = camera_from_manifest(manifest_path);
    if (images.camera && (images.camera->width != size.width || images.camera->height != size.height)) {
      fail("{}: the camera is {}x{}, the images are {}x{}", manifest_path.string(), images.camera->width,
           images.camera->height, size.width, size.height);
    }
  }
  const fs::path mask_path = folder / "mask.png";
  if (fs::exists(mask_path, error)) {
    images.mask = io::read_mask(mask_path);
    if (images.mask.size() != size) {
      fail("{}: mask is {}x{}, images are {}x{}", mask_path.string(), images.mask.cols, images.mask.rows,
           size.width, size.height);
    }
  }
  images.region = cv::Rect(cv::Point(0, 0), size);
  for (const Frame& frame : stack.frames) {
    images.filenames.push_back(frame.filename);
    images.led_ids.push_back(frame.led_id);
  }
  images.frames = std::move(stack.frames);
  return images;
}

namespace {

// Opens image `i`'s file for reading by rows, refusing one of another size or type than the first.
std::unique_ptr<io::RowReader> open_frame(const CalibrationImages& images, std::size_t i,
                                          io::RowReading reading) {
  auto reader = io::open_row_reader(images.folder / images.filenames[i], reading);
  if (reader->size() != images.image_size || reader->type() != images.image_type) {
    fail("{}: image is {}x{} of type {}, but {} is {}x{} of type {}", reader->path().string(),
         reader->size().width, reader->size().height, reader->type(), images.filenames.front(),
         images.image_size.width, images.image_size.height, images.image_type);
  }
  return reader;
}

}  // namespace

void for_each_calibration_image(const CalibrationImages& index, const cv::Rect& region, int threads,
                                const CalibrationImageVisit& visit) {
  const cv::Rect whole(cv::Point(0, 0), index.image_size);
  if (region.empty() || (region & whole) != region)
    fail("{}: region {}x{} at ({}, {}) is not inside the {}x{} images", index.folder.string(), region.width,
         region.height, region.x, region.y, whole.width, whole.height);
  parallel_chunks(index.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Frame frame = index.frames[i];
      cv::Mat rows, grey, saturated;
      open_frame(index, i, io::RowReading::kOnce)->read(region.y, region.height, rows);
      frame.image = rows.colRange(region.x, region.x + region.width);
      convert(frame, &grey, &saturated);
      visit(i, grey, saturated);
    }
  });
}

void load_calibration_pixels(CalibrationImages& images, const cv::Rect& region, int threads) {
  std::vector<cv::Mat> grey(images.size()), saturated(images.size());
  for_each_calibration_image(images, region, threads, [&](std::size_t i, const cv::Mat& g, const cv::Mat& s) {
    grey[i] = g;
    saturated[i] = s;
  });
  images.region = region;
  images.grey = std::move(grey);
  images.saturated = std::move(saturated);
}

CalibrationImages load_calibration_images(const fs::path& folder, int min_images, int threads) {
  CalibrationImages images = load_calibration_index(folder, min_images);
  load_calibration_pixels(images, cv::Rect(cv::Point(0, 0), images.image_size), threads);
  return images;
}

CalibrationRows::CalibrationRows(const CalibrationImages& index, int threads)
    : index_(index), threads_(threads), readers_(index.size()) {
  // Opening decodes a file that decodes only whole (camera RAW): one per thread at a time.
  parallel_chunks(index.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) readers_[i] = open_frame(index, i, io::RowReading::kInBands);
  });
}

CalibrationRows::~CalibrationRows() = default;

void CalibrationRows::read(int y0, int rows, const cv::Range& columns, std::vector<cv::Mat>& grey,
                           std::vector<cv::Mat>& saturated) {
  grey.resize(readers_.size());
  saturated.resize(readers_.size());
  parallel_chunks(readers_.size(), threads_, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Frame frame = index_.frames[i];
      readers_[i]->read(y0, rows, frame.image);
      frame.image = frame.image.colRange(columns);
      convert(frame, &grey[i], &saturated[i]);
    }
  });
}

std::size_t CalibrationRows::bytes_per_pixel() const { return readers_.size() * (12 + 4 + 1); }

CalibrationViews calibration_views(const CalibrationImages& images, int threads, std::size_t band_bytes) {
  const cv::Size size = images.image_size;
  CalibrationRows frames(images, threads);
  const std::size_t row_bytes = static_cast<std::size_t>(size.width) * frames.bytes_per_pixel();
  const int band_rows = static_cast<int>(std::clamp<std::size_t>(
      band_bytes / std::max<std::size_t>(row_bytes, 1), 1, static_cast<std::size_t>(size.height)));
  CalibrationViews views{cv::Mat(size, CV_32FC1), cv::Mat(size, CV_32FC1)};
  std::vector<cv::Mat> grey, saturated;
  for (int y0 = 0; y0 < size.height; y0 += band_rows) {
    const int rows = std::min(band_rows, size.height - y0);
    frames.read(y0, rows, cv::Range(0, size.width), grey, saturated);
    median_image(grey, threads).copyTo(views.median.rowRange(y0, y0 + rows));
    max_image(grey).copyTo(views.maximum.rowRange(y0, y0 + rows));
  }
  return views;
}

cv::Mat median_image(const std::vector<cv::Mat>& images, int threads) {
  if (images.empty()) fail("median_image: no images");
  const cv::Size size = images.front().size();
  cv::Mat median(size, CV_32FC1);
  const std::size_t n = images.size();
  parallel_chunks(static_cast<std::size_t>(size.height), threads,
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
