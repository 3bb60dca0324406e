#pragma once
// The GPIO world as the firmware sees it: a chip with named lines, output
// lines set together, and input lines read as timestamped edges. Backends:
// gpiod:CHIP (hw/, libgpiod) and sim:PATH (sim/, lightstage-sim's virtual
// chip); the firmware opens one by URI.

#include "lightstage/common/error.hpp"

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace lightstage::gpio {

class GpioError : public Error {
 public:
  using Error::Error;
};

struct ChipInfo {
  std::string label;                    // e.g. "pinctrl-bcm2711" or "lightstage-sim"
  std::vector<std::string> line_names;  // by offset; "" when unnamed
  std::vector<std::string> consumers;   // by offset; "" when the line is free
};

struct EdgeEvent {
  unsigned offset = 0;
  bool rising = false;    // true: the line became active (active_low already applied)
  std::int64_t t_ns = 0;  // CLOCK_MONOTONIC
};

// Output lines requested together; values are logical (1 = active), in
// request order. A backend sets all of them as one operation.
class OutputLines {
 public:
  virtual ~OutputLines() = default;
  // `t_ns` is the caller's timestamp for the change (CLOCK_MONOTONIC); backends
  // that record a timeline (the sim) keep it. Throws GpioError.
  virtual void set(std::span<const int> values, std::int64_t t_ns) = 0;
  virtual std::size_t size() const = 0;
};

// One input line with edge events (both edges).
class EdgeInput {
 public:
  virtual ~EdgeInput() = default;
  // The next edge, or nullopt once CLOCK_MONOTONIC passes `deadline_ns`. Throws GpioError.
  virtual std::optional<EdgeEvent> wait_until(std::int64_t deadline_ns) = 0;
  // Drops edges already queued (before a new exposure).
  virtual void drain() = 0;
  // Makes every edge that has happened by now readable, so a reader that woke late can still
  // see the ones that came in time. The kernel queues edges as they happen (nothing to do);
  // the sim sends them over a socket and answers a round trip only after every edge due by then.
  virtual void catch_up() {}
};

class Chip {
 public:
  virtual ~Chip() = default;
  virtual ChipInfo info() const = 0;
  // Offset of the line called `name`, if the chip has one.
  std::optional<unsigned> find_line(std::string_view name) const;
  // Requests outputs, initially at `initial` (logical values; all 0 if empty).
  // Throws GpioError naming the line when it does not exist or is busy.
  virtual std::unique_ptr<OutputLines> request_outputs(std::span<const unsigned> offsets,
                                                       std::span<const bool> active_low,
                                                       std::span<const int> initial,
                                                       const std::string& consumer) = 0;
  virtual std::unique_ptr<EdgeInput> request_edges(unsigned offset, bool active_low,
                                                   const std::string& consumer) = 0;
};

}  // namespace lightstage::gpio
