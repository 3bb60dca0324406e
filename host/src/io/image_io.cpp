#include "lightstage/host/io/image_io.hpp"

#include "io/file_extension.hpp"
#include "io/image_header.hpp"
#include "io/row_readers.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/jpeg_image.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/raw_image.hpp"
#include "lightstage/host/io/row_writer.hpp"
#include "lightstage/host/io/tiff_image.hpp"

#include <system_error>

namespace lightstage::io {
namespace {

std::string describe_type(const cv::Mat& image) {
  return fmt::format("{}-bit depth code {}, {} channel(s)", image.elemSize1() * 8, image.depth(),
                     image.channels());
}

}  // namespace

cv::Mat read_image(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) fail("{}: no such file", path.string());
  if (!std::filesystem::is_regular_file(path, error)) fail("{}: not a regular file", path.string());
  if (lower_extension(path) == ".pfm") return read_pfm(path);
  if (is_raw_file(path)) return read_raw(path).image;
  if (is_tiff_file(path)) return read_tiff(path);
  if (is_png_file(path)) return read_png(path);
  if (is_jpeg_file(path)) return read_jpeg(path);
  fail("{}: not a readable image (PNG, JPEG, TIFF, PFM or camera RAW expected)", path.string());
}

void write_png(const std::filesystem::path& path, const cv::Mat& image) {
  if (image.empty()) fail("{}: cannot write an empty image", path.string());
  if ((image.depth() != CV_8U && image.depth() != CV_16U) ||
      (image.channels() != 1 && image.channels() != 3)) {
    fail("{}: cannot write as PNG: {}; expected 8- or 16-bit with 1 or 3 channels", path.string(),
         describe_type(image));
  }
  const auto writer = open_png_writer(path, image.size(), image.type());
  writer->write(image);
  writer->commit();
}

void write_png16(const std::filesystem::path& path, const cv::Mat& image) {
  if (image.depth() != CV_16U) {
    fail("{}: expected a 16-bit image to write, got {}", path.string(), describe_type(image));
  }
  write_png(path, image);
}

}  // namespace lightstage::io
