#pragma once
// A byte link between host and controller (TCP, Unix socket, serial line,
// USB bulk endpoints), and a listener that accepts them. Backends live in
// hw/ (hw/include/lightstage/hw/links.hpp opens them by URI).

#include "lightstage/common/error.hpp"

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

namespace lightstage {

// The peer closed the link, or the link failed (reset, device gone).
class LinkClosed : public Error {
 public:
  using Error::Error;
};

class ByteLink {
 public:
  virtual ~ByteLink() = default;
  // Reads up to buffer.size() bytes, waiting at most `timeout`; returns 0 on
  // timeout. Throws LinkClosed at end of stream or on failure.
  virtual std::size_t read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) = 0;
  // Writes every byte or throws LinkClosed.
  virtual void write(std::span<const std::uint8_t> bytes) = 0;
  // Closes the link now; later reads and writes throw LinkClosed. Safe to call
  // from another thread to wake a reader.
  virtual void shutdown() = 0;
  // For messages: "tcp:127.0.0.1:7700 (peer 127.0.0.1:51234)".
  virtual std::string describe() const = 0;
};

class LinkListener {
 public:
  virtual ~LinkListener() = default;
  // The next connection, or nullptr after `timeout`.
  virtual std::unique_ptr<ByteLink> accept(std::chrono::milliseconds timeout) = 0;
  virtual std::string describe() const = 0;
};

}  // namespace lightstage
