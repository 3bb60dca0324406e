#pragma once
// A ByteLink that hands out the fuzz input in the chunks the target cut it
// into (one chunk at most per read), then reports the end of the stream:
// what the protocol, controller and sim GPIO targets read their peer from.

#include "lightstage/common/link.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <string>
#include <vector>

namespace lightstage::fuzz {

class ChunkedLink final : public ByteLink {
 public:
  explicit ChunkedLink(std::deque<std::vector<std::uint8_t>> chunks) : chunks_(std::move(chunks)) {}
  std::size_t read(std::span<std::uint8_t> buffer, std::chrono::milliseconds) override {
    if (chunks_.empty()) throw LinkClosed("fuzz: end of input");
    std::vector<std::uint8_t>& chunk = chunks_.front();
    const std::size_t n = std::min(buffer.size(), chunk.size());
    std::copy_n(chunk.begin(), n, buffer.begin());
    chunk.erase(chunk.begin(), chunk.begin() + static_cast<std::ptrdiff_t>(n));
    if (chunk.empty()) chunks_.pop_front();
    return n;
  }
  void write(std::span<const std::uint8_t>) override {}
  void shutdown() override { chunks_.clear(); }
  std::string describe() const override { return "fuzz"; }

 private:
  std::deque<std::vector<std::uint8_t>> chunks_;
};

}  // namespace lightstage::fuzz
