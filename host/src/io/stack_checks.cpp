#include "io/stack_checks.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/printable.hpp"
#include "lightstage/host/io/stack_io.hpp"

#include <cmath>
#include <unordered_map>

namespace lightstage::io {
namespace {

std::string size_text(const ImageHeader& header) { return fmt::format("{}x{}", header.width, header.height); }

}  // namespace

void check_listed_names(const std::filesystem::path& names_path, const std::vector<TextLine>& names) {
  if (names.size() > kMaxStackImages) {
    fail("{}: {} images listed, at most {} are read", names_path.string(), names.size(), kMaxStackImages);
  }
  std::unordered_map<std::string, int> first_line;
  for (const auto& name : names) {
    const auto [it, fresh] = first_line.emplace(name.text, name.number);
    if (!fresh) {
      fail("{}:{}: '{}' is listed again (first at line {})", names_path.string(), name.number,
           printable(name.text), it->second);
    }
  }
}

ImageHeader check_frame_headers(const std::filesystem::path& dir, const std::vector<std::string>& files,
                                const std::optional<cv::Size>& manifest_size,
                                const std::filesystem::path& manifest_path) {
  ImageHeader first;
  for (std::size_t i = 0; i < files.size(); ++i) {
    const std::filesystem::path path = dir / files[i];
    const ImageHeader header = read_image_header(path);
    if (header.width > kMaxImageSide || header.height > kMaxImageSide) {
      fail("{}: image declares {}, larger than the {}x{} a stack may hold", path.string(), size_text(header),
           kMaxImageSide, kMaxImageSide);
    }
    if (i == 0) {
      first = header;
      if (manifest_size && (header.width != manifest_size->width || header.height != manifest_size->height)) {
        fail("{}: image is {}, but {} says {}x{}", path.string(), size_text(header), manifest_path.string(),
             manifest_size->width, manifest_size->height);
      }
    } else if (header.width != first.width || header.height != first.height) {
      fail("{}: image is {}, but {} is {}", path.string(), size_text(header), files.front(),
           size_text(first));
    }
  }
  return first;
}

void check_declared_size(const std::filesystem::path& path, const ImageHeader& frames,
                         const std::string& what) {
  const ImageHeader header = read_image_header(path);
  if (header.width != frames.width || header.height != frames.height) {
    fail("{}: {} is {}, images are {}", path.string(), what, size_text(header), size_text(frames));
  }
}

std::string image_type_text(int type) {
  const int depth = CV_MAT_DEPTH(type);
  return fmt::format("{} {}",
                     depth == CV_8U    ? "8-bit"
                     : depth == CV_16U ? "16-bit"
                                       : "float",
                     CV_MAT_CN(type) == 1 ? "grey" : "RGB");
}

void check_finite_pixels(const std::filesystem::path& path, const cv::Mat& image, int first_row) {
  if (image.depth() != CV_32F) return;
  const int values = image.cols * image.channels();
  for (int y = 0; y < image.rows; ++y) {
    const float* row = image.ptr<float>(y);
    for (int v = 0; v < values; ++v) {
      if (!std::isfinite(row[v])) {
        fail("{}: pixel ({}, {}) is {}; stack images must hold finite values", path.string(),
             v / image.channels(), first_row + y,
             std::isnan(row[v]) ? "NaN"
             : row[v] > 0       ? "+Inf"
                                : "-Inf");
      }
    }
  }
}

}  // namespace lightstage::io
