#include "report/html.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/io/image_io.hpp"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <memory>

namespace lightstage::report {

std::string escape_html(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string base64(std::span<const std::uint8_t> bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const std::uint32_t v =
        (std::uint32_t{bytes[i]} << 16) | (std::uint32_t{bytes[i + 1]} << 8) | bytes[i + 2];
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  const std::size_t rest = bytes.size() - i;
  if (rest > 0) {
    std::uint32_t v = std::uint32_t{bytes[i]} << 16;
    if (rest == 2) v |= std::uint32_t{bytes[i + 1]} << 8;
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += rest == 2 ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string png_data_uri(const cv::Mat& image) {
  const std::string png = io::encode_png(image, "report");
  return "data:image/png;base64," + base64({reinterpret_cast<const std::uint8_t*>(png.data()), png.size()});
}

namespace {

// One piece as raw deflate, compressed on its own (no window from the piece
// before): the last finished (BFINAL), every other ending in a sync flush's
// empty stored block on a byte boundary, so that the pieces in order are one
// deflate stream (RFC 1951).
std::vector<std::uint8_t> deflate_piece(std::span<const std::uint8_t> piece, bool last) {
  z_stream z{};
  // Level 1: the pages come out within a few percent of zlib's default level 6, in a third of the
  // time (docs/report.md).
  if (deflateInit2(&z, Z_BEST_SPEED, Z_DEFLATED, -MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    fail("report: zlib cannot start a compression ({})", z.msg != nullptr ? z.msg : "out of memory");
  const std::unique_ptr<z_stream, int (*)(z_stream*)> end(&z, deflateEnd);
  // deflateBound covers a finished stream; a sync flush adds at most an empty stored block.
  std::vector<std::uint8_t> out(deflateBound(&z, static_cast<uLong>(piece.size())) + 16);
  z.next_in = const_cast<Bytef*>(piece.data());  // zlib's API is not const; it only reads
  z.avail_in = static_cast<uInt>(piece.size());
  z.next_out = out.data();
  z.avail_out = static_cast<uInt>(out.size());
  const int status = deflate(&z, last ? Z_FINISH : Z_SYNC_FLUSH);
  const bool done = last ? status == Z_STREAM_END : status == Z_OK && z.avail_in == 0 && z.avail_out > 0;
  if (!done) fail("report: zlib compression of {} bytes failed (status {})", piece.size(), status);
  out.erase(out.end() - static_cast<std::ptrdiff_t>(z.avail_out), out.end());  // shrinks only
  return out;
}

}  // namespace

std::vector<std::uint8_t> zlib_compress(std::span<const std::uint8_t> bytes) {
  // Side by side: a 2048² result's viewer planes (23 MB) were the solve's last half second on one core.
  const std::size_t pieces = std::max<std::size_t>(1, (bytes.size() + kDeflatePiece - 1) / kDeflatePiece);
  const auto piece = [&](std::size_t i) {
    const std::size_t begin = i * kDeflatePiece;
    return bytes.subspan(begin, std::min(kDeflatePiece, bytes.size() - begin));
  };
  std::vector<std::vector<std::uint8_t>> deflated(pieces);
  std::vector<uLong> checks(pieces);
  parallel_for(static_cast<int>(pieces), 0, [&](int i) {
    const auto index = static_cast<std::size_t>(i);
    const std::span<const std::uint8_t> part = piece(index);
    deflated[index] = deflate_piece(part, index + 1 == pieces);
    checks[index] = adler32(adler32(0, nullptr, 0), part.data(), static_cast<uInt>(part.size()));
  });
  // RFC 1950: CMF (deflate, a 32 KiB window) and FLG (the fastest level, a check that makes the
  // pair a multiple of 31); the pieces; the Adler-32 of all the bytes, most significant first.
  std::size_t total = 2 + 4;
  for (const auto& part : deflated) total += part.size();
  std::vector<std::uint8_t> out;
  out.reserve(total);  // each piece freed once copied
  out.push_back(0x78);
  out.push_back(0x01);
  uLong check = checks[0];
  for (std::size_t i = 0; i < pieces; ++i) {
    out.insert(out.end(), deflated[i].begin(), deflated[i].end());
    std::vector<std::uint8_t>().swap(deflated[i]);
    if (i > 0) check = adler32_combine(check, checks[i], static_cast<z_off_t>(piece(i).size()));
  }
  for (int shift = 24; shift >= 0; shift -= 8)
    out.push_back(static_cast<std::uint8_t>((check >> shift) & 0xff));
  return out;
}

std::string format_number(double value, int digits) {
  if (!std::isfinite(value)) return std::isnan(value) ? "n/a" : (value > 0 ? "∞" : "−∞");
  if (value == 0) return "0";
  const double magnitude = std::fabs(value);
  if (magnitude >= 1e7 || magnitude < 1e-4) return fmt::format("{:.{}g}", value, digits);
  const int leading = static_cast<int>(std::floor(std::log10(magnitude)));  // 2 for 123, -3 for 0.00123
  const int decimals = std::max(0, digits - 1 - leading);
  std::string text = fmt::format("{:.{}f}", value, decimals);
  if (text.find('.') != std::string::npos) {
    while (text.back() == '0') text.pop_back();
    if (text.back() == '.') text.pop_back();
  }
  return text;
}

}  // namespace lightstage::report
