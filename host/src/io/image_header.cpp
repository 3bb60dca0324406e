#include "io/image_header.hpp"

#include "io/file_extension.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/raw_image.hpp"
#include "lightstage/host/io/tiff_image.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <fstream>
#include <string>
#include <system_error>

namespace lightstage::io {
namespace {

// Enough for any PFM header a tool writes; a longer one is refused rather than read on.
constexpr std::size_t kHeaderBytes = 4096;

constexpr std::array<unsigned char, 8> kPngSignature = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

std::uint32_t big_endian(const std::string& bytes, std::size_t at) {
  std::uint32_t value = 0;
  for (std::size_t i = 0; i < 4; ++i) value = (value << 8) | static_cast<unsigned char>(bytes[at + i]);
  return value;
}

ImageHeader png_header(const std::filesystem::path& path, const std::string& bytes) {
  // Signature, then the IHDR chunk: length 13, "IHDR", width and height (big-endian).
  if (bytes.size() < 24 || bytes.compare(12, 4, "IHDR") != 0) {
    fail("{}: not a readable image (truncated or malformed PNG header)", path.string());
  }
  // Bit depth and colour type follow; read_image gives 8 or 16 bits, grey or BGR (palette, alpha: BGR).
  const int depth_bytes = bytes.size() > 24 && bytes[24] == 16 ? 2 : 1;
  const int channels = bytes.size() > 25 && (bytes[25] & 0x6) != 0 ? 3 : 1;
  const ImageHeader header{big_endian(bytes, 16), big_endian(bytes, 20), depth_bytes * channels};
  if (header.width == 0 || header.height == 0 || header.width > 0x7fffffff || header.height > 0x7fffffff) {
    fail("{}: not a readable image (PNG header declares {}x{})", path.string(), header.width, header.height);
  }
  return header;
}

bool has_png_signature(const std::string& bytes) {
  return bytes.size() >= kPngSignature.size() &&
         std::equal(kPngSignature.begin(), kPngSignature.end(), bytes.begin(),
                    [](unsigned char a, char b) { return a == static_cast<unsigned char>(b); });
}

}  // namespace

bool is_png_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes(kPngSignature.size(), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<std::size_t>(in.gcount()));
  return has_png_signature(bytes);
}

ImageHeader read_image_header(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) fail("{}: no such file", path.string());
  if (!std::filesystem::is_regular_file(path, error)) fail("{}: not a regular file", path.string());
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("{}: cannot open (not readable)", path.string());
  std::string bytes(kHeaderBytes, '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<std::size_t>(in.gcount()));

  if (lower_extension(path) == ".pfm") {
    const PfmHeader pfm = parse_pfm_header(path, bytes);
    return {pfm.width, pfm.height, pfm.channels * 4};
  }
  if (is_raw_file(path) || is_tiff_file(path)) {
    const cv::Size size = is_raw_file(path) ? read_raw_size(path) : read_tiff_size(path);
    return {size.width, size.height};
  }
  if (has_png_signature(bytes)) return png_header(path, bytes);
  fail("{}: not a readable image (stack images are PNG, PFM, TIFF or camera RAW)", path.string());
}

}  // namespace lightstage::io
