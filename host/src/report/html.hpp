#pragma once
// Small pieces of a self-contained HTML page: escaping, base64, images as
// data URIs, zlib compression of embedded binary data.

#include <opencv2/core.hpp>

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace lightstage::report {

// Escapes & < > " ' for text and attribute values.
std::string escape_html(std::string_view text);

// Standard base64 (RFC 4648, with padding).
std::string base64(std::span<const std::uint8_t> bytes);

// "data:image/png;base64,..." of io::encode_png(image): 8- or 16-bit, 1, 3 or 4 channels (BGR/BGRA).
std::string png_data_uri(const cv::Mat& image);

// zlib stream (RFC 1950), what the browser's DecompressionStream("deflate") reads,
// deflated in pieces of kDeflatePiece bytes side by side. The split depends on
// the size alone: the same bytes always give the same stream.
inline constexpr std::size_t kDeflatePiece = std::size_t{4} << 20;
std::vector<std::uint8_t> zlib_compress(std::span<const std::uint8_t> bytes);

// Numbers for people: at most `digits` significant digits, no exponent for ordinary sizes.
std::string format_number(double value, int digits = 4);

}  // namespace lightstage::report
