#include "lightstage/host/io/pfm.hpp"

#include "lightstage/common/error.hpp"
#include "util/atomic_file.hpp"

#include <opencv2/core.hpp>

#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>
#include <vector>

namespace lightstage::io {
namespace {

// Reads the next whitespace-delimited header token.
bool next_token(const std::string& data, std::size_t& pos, std::string& token) {
  while (pos < data.size() && std::isspace(static_cast<unsigned char>(data[pos]))) ++pos;
  const std::size_t start = pos;
  while (pos < data.size() && !std::isspace(static_cast<unsigned char>(data[pos]))) ++pos;
  token = data.substr(start, pos - start);
  return !token.empty();
}

// Parses the whole token as a number.
template <typename T>
bool parse_whole(const std::string& token, T& value) {
  const char* begin = token.data();
  const char* end = begin + token.size();
  const auto [next, error] = std::from_chars(begin, end, value);
  return error == std::errc() && next == end;
}

std::uint32_t byte_swap(std::uint32_t v) {
  return ((v & 0xffu) << 24) | ((v & 0xff00u) << 8) | ((v >> 8) & 0xff00u) | (v >> 24);
}

}  // namespace

cv::Mat read_pfm(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("{}: cannot open (no such file or not readable)", path.string());
  const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());

  std::size_t pos = 0;
  std::string magic, width_text, height_text, scale_text;
  if (!next_token(data, pos, magic) || (magic != "PF" && magic != "Pf")) {
    fail("{}: not a PFM file (expected 'PF' or 'Pf' at the start)", path.string());
  }
  if (!next_token(data, pos, width_text) || !next_token(data, pos, height_text) ||
      !next_token(data, pos, scale_text)) {
    fail("{}: truncated PFM header", path.string());
  }
  int width = 0, height = 0;
  double scale = 0;
  if (!parse_whole(width_text, width) || !parse_whole(height_text, height) ||
      !parse_whole(scale_text, scale)) {
    fail("{}: malformed PFM header '{} {} {}'", path.string(), width_text, height_text, scale_text);
  }
  if (width <= 0 || height <= 0 || width > 1 << 16 || height > 1 << 16) {
    fail("{}: bad PFM size {}x{}", path.string(), width, height);
  }
  if (scale == 0 || !std::isfinite(scale)) fail("{}: bad PFM scale '{}'", path.string(), scale_text);
  ++pos;  // exactly one whitespace character ends the header

  const int channels = magic == "PF" ? 3 : 1;
  const std::size_t row_values = static_cast<std::size_t>(width) * static_cast<std::size_t>(channels);
  const std::size_t bytes = row_values * static_cast<std::size_t>(height) * sizeof(float);
  if (pos > data.size() || data.size() - pos < bytes) {
    fail("{}: truncated PFM data ({} bytes, expected {})", path.string(),
         pos > data.size() ? 0 : data.size() - pos, bytes);
  }
  const bool file_little = scale < 0;
  const bool swap = file_little != (std::endian::native == std::endian::little);

  cv::Mat image(height, width, CV_MAKETYPE(CV_32F, channels));
  std::vector<std::uint32_t> row(row_values);
  for (int file_row = 0; file_row < height; ++file_row) {
    std::memcpy(row.data(),
                data.data() + pos + static_cast<std::size_t>(file_row) * row_values * sizeof(float),
                row_values * sizeof(float));
    if (swap) {
      for (auto& v : row) v = byte_swap(v);
    }
    // Rows are stored bottom-to-top; channels are RGB on disk, BGR in memory.
    auto* out = image.ptr<float>(height - 1 - file_row);
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < channels; ++c) {
        const int disk_channel = channels == 3 ? 2 - c : 0;
        out[x * channels + c] =
            std::bit_cast<float>(row[static_cast<std::size_t>(x * channels + disk_channel)]);
      }
    }
  }
  return image;
}

void write_pfm(const std::filesystem::path& path, const cv::Mat& image) {
  if (image.empty() || image.depth() != CV_32F || (image.channels() != 1 && image.channels() != 3)) {
    fail("{}: cannot write as PFM: expected CV_32FC1 or CV_32FC3, got depth code {} with {} channel(s)",
         path.string(), image.depth(), image.channels());
  }
  const int channels = image.channels();
  std::string data = fmt::format("{}\n{} {}\n-1\n", channels == 3 ? "PF" : "Pf", image.cols, image.rows);
  const std::size_t header = data.size();
  const std::size_t row_values = static_cast<std::size_t>(image.cols) * static_cast<std::size_t>(channels);
  data.resize(header + row_values * static_cast<std::size_t>(image.rows) * sizeof(float));
  std::vector<float> row(row_values);
  for (int file_row = 0; file_row < image.rows; ++file_row) {
    const auto* in = image.ptr<float>(image.rows - 1 - file_row);
    for (int x = 0; x < image.cols; ++x) {
      for (int c = 0; c < channels; ++c) {
        row[static_cast<std::size_t>(x * channels + c)] = in[x * channels + (channels == 3 ? 2 - c : 0)];
      }
    }
    if constexpr (std::endian::native != std::endian::little) {
      for (auto& v : row) v = std::bit_cast<float>(byte_swap(std::bit_cast<std::uint32_t>(v)));
    }
    std::memcpy(data.data() + header + static_cast<std::size_t>(file_row) * row_values * sizeof(float),
                row.data(), row_values * sizeof(float));
  }
  util::write_text_atomic(path, data);
}

}  // namespace lightstage::io
