#pragma once
// The checks load_stack makes before it decodes a stack's images, so a hostile
// or broken folder costs neither minutes nor gigabytes: the number of listed
// images and repeated names, every image's declared size (from its header)
// against the first image, the manifest and the caps in stack_io.hpp; and,
// after decoding, that float frames hold only finite values.

#include "io/image_header.hpp"
#include "io/text_table.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::io {

// Whether `path` exists; an unreadable parent counts as "no".
inline bool file_exists(const std::filesystem::path& path) {
  std::error_code error;
  return std::filesystem::exists(path, error);
}

// Refuses more than kMaxStackImages entries and a name listed twice.
void check_listed_names(const std::filesystem::path& names_path, const std::vector<TextLine>& names);

// Reads the header of each of `files` (inside `dir`) and refuses a size over
// kMaxImageSide, one that differs from the first file's, or from `manifest_size`
// (declared by `manifest_path`). Returns the common size.
ImageHeader check_frame_headers(const std::filesystem::path& dir, const std::vector<std::string>& files,
                                const std::optional<cv::Size>& manifest_size,
                                const std::filesystem::path& manifest_path);

// Refuses `path` (the mask, ground truth or a dark frame: `what`) when its
// header declares another size than the frames'.
void check_declared_size(const std::filesystem::path& path, const ImageHeader& frames,
                         const std::string& what);

// Refuses a float image holding NaN or infinity, naming the first such pixel
// (x, y); `image` may be a band whose row 0 is row `first_row` of the file.
void check_finite_pixels(const std::filesystem::path& path, const cv::Mat& image, int first_row = 0);

// "16-bit RGB", "float grey", ... for an image of OpenCV type `type`.
std::string image_type_text(int type);

}  // namespace lightstage::io
