#include "lightstage/common/framing.hpp"

#include "lightstage/common/error.hpp"

#include <fmt/format.h>
#include <zlib.h>

#include <algorithm>

namespace lightstage::protocol {
namespace {

std::uint32_t crc32_of(std::span<const std::uint8_t> bytes) {
  return static_cast<std::uint32_t>(::crc32(::crc32(0L, Z_NULL, 0), bytes.data(), static_cast<uInt>(bytes.size())));
}

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

std::uint32_t get_u32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}

}  // namespace

std::vector<std::uint8_t> encode_frame(std::span<const std::uint8_t> payload) {
  if (payload.size() > kMaxPayload) {
    throw Error(fmt::format("frame payload of {} bytes exceeds the {} byte limit", payload.size(), kMaxPayload));
  }
  std::vector<std::uint8_t> out;
  out.reserve(kHeaderSize + payload.size() + kTrailerSize);
  out.push_back(kMagic0);
  out.push_back(kMagic1);
  put_u32(out, static_cast<std::uint32_t>(payload.size()));
  out.insert(out.end(), payload.begin(), payload.end());
  put_u32(out, crc32_of(payload));
  return out;
}

void FrameDecoder::feed(std::span<const std::uint8_t> bytes) {
  compact();
  buffer_.insert(buffer_.end(), bytes.begin(), bytes.end());
}

void FrameDecoder::compact() {
  // Drop consumed bytes once they dominate, so feeding stays amortised O(n).
  if (start_ > 0 && start_ * 2 >= buffer_.size()) {
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(start_));
    start_ = 0;
  }
}

std::optional<FrameDecoder::Frame> FrameDecoder::next() {
  const std::uint8_t* data = buffer_.data() + start_;
  const std::size_t size = buffer_.size() - start_;
  if (size == 0) return std::nullopt;
  // Resynchronise: skip to the next magic.
  std::size_t skip = 0;
  while (skip < size && !(data[skip] == kMagic0 && (skip + 1 == size || data[skip + 1] == kMagic1))) ++skip;
  if (skip > 0) {
    start_ += skip;
    return Frame{{}, fmt::format("dropped {} byte(s) of garbage before a frame", skip)};
  }
  if (size < kHeaderSize) return std::nullopt;
  const std::uint32_t length = get_u32(data + 2);
  if (length > kMaxPayload) {
    start_ += 1;  // not a real frame start: look for the next magic
    return Frame{{}, fmt::format("frame length {} exceeds the {} byte limit", length, kMaxPayload)};
  }
  const std::size_t total = kHeaderSize + length + kTrailerSize;
  if (size < total) return std::nullopt;
  const std::span<const std::uint8_t> payload(data + kHeaderSize, length);
  const std::uint32_t expected = get_u32(data + kHeaderSize + length);
  const std::uint32_t actual = crc32_of(payload);
  if (expected != actual) {
    start_ += 1;  // the header may itself be corrupt: resynchronise from the next byte
    return Frame{{}, fmt::format("frame of {} bytes failed its CRC (0x{:08x} != 0x{:08x})", length, actual, expected)};
  }
  Frame frame{std::vector<std::uint8_t>(payload.begin(), payload.end()), {}};
  start_ += total;
  return frame;
}

}  // namespace lightstage::protocol
