#include "lightstage/common/framing.hpp"

#include "lightstage/common/error.hpp"

#include <fmt/format.h>
#include <zlib.h>

#include <algorithm>

namespace lightstage::protocol {
namespace {

std::uint32_t crc32_of(std::span<const std::uint8_t> bytes) {
  return static_cast<std::uint32_t>(
      ::crc32(::crc32(0L, Z_NULL, 0), bytes.data(), static_cast<uInt>(bytes.size())));
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
    throw Error(
        fmt::format("frame payload of {} bytes exceeds the {} byte limit", payload.size(), kMaxPayload));
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
  // A run of bad bytes (garbage, a bogus header, a frame failing its CRC, more
  // garbage...) is skipped in one go and reported once, so a peer that answers
  // every report with an error reply sends one reply per damaged frame, not one
  // per byte of it. A good frame right after the run waits for the next call.
  std::size_t dropped = 0;
  std::string reason;  // why the first of the dropped bytes went
  const auto drop = [&](std::size_t count, std::string why) {
    if (dropped == 0) reason = std::move(why);
    dropped += count;
    advance(count);
  };
  const auto report = [&]() -> std::optional<Frame> {
    if (dropped == 0) return std::nullopt;
    return Frame{{}, fmt::format("dropped {} byte(s): {}", dropped, reason)};
  };
  for (;;) {
    const std::uint8_t* data = buffer_.data() + start_;
    const std::size_t size = buffer_.size() - start_;
    if (size == 0) return report();
    // Resynchronise: skip to the next magic (a lone 'L' at the end may be one).
    std::size_t skip = 0;
    while (skip < size && !(data[skip] == kMagic0 && (skip + 1 == size || data[skip + 1] == kMagic1))) ++skip;
    if (skip > 0) {
      drop(skip, "garbage outside a frame");
      continue;
    }
    if (size < kHeaderSize) return report();
    const std::uint32_t length = get_u32(data + 2);
    if (length > kMaxPayload) {
      // Not a real frame start: look for the next magic.
      drop(1, fmt::format("frame length {} exceeds the {} byte limit", length, kMaxPayload));
      continue;
    }
    const std::size_t total = kHeaderSize + length + kTrailerSize;
    if (size < total) {
      if (const auto later = later_complete_frame()) {
        drop(*later, fmt::format("a frame of {} bytes was cut short by the next frame", length));
        continue;
      }
      return report();
    }
    const std::span<const std::uint8_t> payload(data + kHeaderSize, length);
    const std::uint32_t expected = get_u32(data + kHeaderSize + length);
    const std::uint32_t actual = crc32_of(payload);
    if (expected != actual) {
      // The header may itself be corrupt: resynchronise from the next byte.
      drop(1,
           fmt::format("frame of {} bytes failed its CRC (0x{:08x} != 0x{:08x})", length, actual, expected));
      continue;
    }
    if (dropped > 0) return report();
    Frame frame{std::vector<std::uint8_t>(payload.begin(), payload.end()), {}};
    advance(total);
    return frame;
  }
}

void FrameDecoder::advance(std::size_t count) {
  start_ += count;
  lookahead_ = 0;
}

std::optional<std::size_t> FrameDecoder::later_complete_frame() {
  const std::uint8_t* data = buffer_.data() + start_;
  const std::size_t size = buffer_.size() - start_;
  // Candidates start after our magic. Everything before `at` is settled:
  // no magic there, or a frame that is complete and failed its CRC. The scan
  // stops at the first candidate still incomplete, to look at it again later.
  std::size_t at = std::max<std::size_t>(lookahead_, 1);
  for (; at + 1 < size; ++at) {
    if (data[at] != kMagic0 || data[at + 1] != kMagic1) continue;
    if (size - at < kHeaderSize) break;
    const std::uint32_t length = get_u32(data + at + 2);
    if (length > kMaxPayload) continue;
    if (size - at < kHeaderSize + length + kTrailerSize) break;
    if (crc32_of(std::span(data + at + kHeaderSize, length)) == get_u32(data + at + kHeaderSize + length)) {
      return at;
    }
  }
  lookahead_ = at;
  return std::nullopt;
}

}  // namespace lightstage::protocol
