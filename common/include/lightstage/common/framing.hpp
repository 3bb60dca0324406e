#pragma once
// Framing for byte streams (serial, TCP, Unix sockets, USB bulk):
//
//   'L' 'S' | length u32 LE | payload (length bytes) | CRC-32 u32 LE of payload
//
// The magic lets a reader resynchronise after garbage; the length is bounded
// so a corrupt header cannot make a reader wait for gigabytes; the CRC (zlib's
// CRC-32) rejects frames damaged on the wire. Payloads are serialized protobuf
// messages (common/proto/lightstage/proto/*.proto).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace lightstage::protocol {

inline constexpr std::uint8_t kMagic0 = 'L';
inline constexpr std::uint8_t kMagic1 = 'S';
inline constexpr std::size_t kHeaderSize = 6;   // magic + length
inline constexpr std::size_t kTrailerSize = 4;  // CRC-32
inline constexpr std::size_t kMaxPayload = 1u << 20;

// Throws lightstage::Error when the payload exceeds kMaxPayload.
std::vector<std::uint8_t> encode_frame(std::span<const std::uint8_t> payload);

// Incremental decoder: feed bytes as they arrive, take frames out.
class FrameDecoder {
 public:
  struct Frame {
    std::vector<std::uint8_t> payload;  // valid when error is empty
    std::string error;                  // why bytes were dropped (bad CRC, oversize length, garbage)
  };

  void feed(std::span<const std::uint8_t> bytes);
  // The next complete frame, or a report of dropped bytes (the decoder has
  // already skipped past them and stays usable; one report covers a whole run
  // of bad bytes as far as they are buffered); nullopt when more bytes are needed.
  // A frame still incomplete when a complete, CRC-valid frame starts after its
  // header is taken as cut short (a sender that died mid-frame) and dropped,
  // so a stale partial frame cannot swallow the next session's messages; so
  // are any further cut-short frames between the two, however many.
  std::optional<Frame> next();
  // Gives up on the incomplete frame at the front (its sender went quiet
  // mid-frame) and resynchronises on the next magic after its start. A report
  // naming how much of it had arrived; nullopt when nothing was buffered.
  std::optional<Frame> abandon_partial();
  std::size_t buffered() const { return buffer_.size() - start_; }

 private:
  void compact();
  void advance(std::size_t count);
  // Offset (from start_) of a complete, CRC-valid frame after the frame start at start_.
  std::optional<std::size_t> later_complete_frame();

  // A later frame start whose bytes have not all arrived yet: looked at again
  // (its CRC checked once) when the buffer reaches its end.
  struct PendingCandidate {
    std::size_t end = 0;  // offset from start_ one past its CRC
    std::size_t at = 0;   // offset from start_ of its magic
    bool operator>(const PendingCandidate& other) const { return end > other.end; }
  };

  std::vector<std::uint8_t> buffer_;
  std::size_t start_ = 0;
  // Offset from start_ below which later_complete_frame() has scanned: every
  // candidate before it is rejected or waits in pending_, so bytes of a long
  // frame arriving piecewise are examined once.
  std::size_t lookahead_ = 0;
  // Min-heap on `end`.
  std::vector<PendingCandidate> pending_;
};

}  // namespace lightstage::protocol
