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

std::optional<FrameDecoder::Frame> FrameDecoder::abandon_partial() {
  const std::size_t size = buffered();
  if (size == 0) return std::nullopt;
  std::string what = fmt::format("{} byte(s) of an incomplete frame", size);
  if (size >= kHeaderSize) {
    const std::uint8_t* data = buffer_.data() + start_;
    what = fmt::format("{} of the {} bytes of a frame", size, kHeaderSize + get_u32(data + 2) + kTrailerSize);
  }
  // Up to the next magic only, so that a frame begun inside the abandoned one
  // is still found.
  const std::uint8_t* data = buffer_.data() + start_;
  std::size_t skip = 1;
  while (skip < size && !(data[skip] == kMagic0 && (skip + 1 == size || data[skip + 1] == kMagic1))) ++skip;
  advance(skip);
  return Frame{{}, fmt::format("abandoned {}: its sender stopped mid-frame", what)};
}

void FrameDecoder::advance(std::size_t count) {
  start_ += count;
  lookahead_ = 0;
  pending_.clear();
}

std::optional<std::size_t> FrameDecoder::later_complete_frame() {
  const std::uint8_t* data = buffer_.data() + start_;
  const std::size_t size = buffer_.size() - start_;
  const auto valid_at = [&](std::size_t at, std::uint32_t length) {
    return crc32_of(std::span(data + at + kHeaderSize, length)) == get_u32(data + at + kHeaderSize + length);
  };
  // Candidates seen before and now complete: the earliest valid one wins.
  std::optional<std::size_t> found;
  while (!pending_.empty() && pending_.front().end <= size) {
    std::pop_heap(pending_.begin(), pending_.end(), std::greater<>());
    const PendingCandidate candidate = pending_.back();
    pending_.pop_back();
    if (valid_at(candidate.at, get_u32(data + candidate.at + 2)) && (!found || candidate.at < *found)) {
      found = candidate.at;
    }
  }
  if (found) return found;
  // New candidates start after our magic. A candidate still incomplete waits
  // in pending_ while the scan goes on, so that a run of frames cut short one
  // after another cannot hide the complete frame behind them.
  std::size_t at = std::max<std::size_t>(lookahead_, 1);
  for (; at + 1 < size; ++at) {
    if (data[at] != kMagic0 || data[at + 1] != kMagic1) continue;
    if (size - at < kHeaderSize) break;
    const std::uint32_t length = get_u32(data + at + 2);
    if (length > kMaxPayload) continue;
    const std::size_t end = at + kHeaderSize + length + kTrailerSize;
    if (size < end) {
      pending_.push_back({end, at});
      std::push_heap(pending_.begin(), pending_.end(), std::greater<>());
      continue;
    }
    if (valid_at(at, length)) {
      lookahead_ = at;
      return at;
    }
  }
  lookahead_ = at;
  return std::nullopt;
}

}  // namespace lightstage::protocol
