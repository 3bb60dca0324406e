#pragma once
// An in-memory gpio::Chip for firmware unit tests: named lines, consumers
// (busy lines are refused), a record of every line change with the caller's
// timestamp, and a camera that answers a trigger edge with strobe edges on
// the chip's clock (real or virtual). Thread-safe.

#include "lightstage/common/clock.hpp"
#include "lightstage/common/gpio.hpp"

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::firmware::testing {

struct LineChange {
  std::int64_t t_ns = 0;
  unsigned offset = 0;
  int value = 0;  // logical (1 = active)
};

struct FakeCamera {
  unsigned trigger = 0;
  unsigned strobe = 0;
  std::int64_t delay_ns = 50'000;        // trigger edge -> exposure start
  std::int64_t exposure_ns = 5'000'000;  // exposure length (strobe high)
  bool lost = false;                     // no strobe at all
};

class FakeChip final : public gpio::Chip {
 public:
  // `names` by offset ("" for unnamed).
  FakeChip(std::vector<std::string> names, Clock& clock, std::string label = "fake-chip");
  // A chip of `count` lines named "" except those in `named` (offset -> name).
  static std::unique_ptr<FakeChip> with_lines(unsigned count, Clock& clock,
                                              const std::map<unsigned, std::string>& named = {});

  gpio::ChipInfo info() const override;
  std::unique_ptr<gpio::OutputLines> request_outputs(std::span<const unsigned> offsets,
                                                     std::span<const bool> active_low,
                                                     std::span<const int> initial,
                                                     const std::string& consumer) override;
  std::unique_ptr<gpio::EdgeInput> request_edges(unsigned offset, bool active_low,
                                                 const std::string& consumer) override;

  void set_camera(const FakeCamera& camera);
  // Marks a line as used by someone else.
  void occupy(unsigned offset, const std::string& consumer);
  // Every set() after the next `n` throws GpioError.
  void fail_after_sets(int n);

  std::vector<LineChange> changes() const;
  std::vector<LineChange> changes_of(unsigned offset) const;
  int value(unsigned offset) const;
  bool active_low(unsigned offset) const;
  std::string consumer(unsigned offset) const;

  // Called by the fake line objects.
  void apply(const std::vector<unsigned>& offsets, std::span<const int> values, std::int64_t t_ns);
  void release(const std::vector<unsigned>& offsets);
  std::optional<gpio::EdgeEvent> next_edge(unsigned offset, std::int64_t deadline_ns);
  void drain(unsigned offset);

 private:
  void claim(unsigned offset, bool low, const std::string& consumer);

  mutable std::mutex mutex_;
  Clock& clock_;
  std::string label_;
  std::vector<std::string> names_;
  std::vector<std::string> consumers_;
  std::vector<int> values_;
  std::vector<bool> active_low_;
  std::vector<LineChange> changes_;
  std::map<unsigned, std::deque<gpio::EdgeEvent>> edges_;
  std::optional<FakeCamera> camera_;
  int sets_left_ = -1;
};

}  // namespace lightstage::firmware::testing
