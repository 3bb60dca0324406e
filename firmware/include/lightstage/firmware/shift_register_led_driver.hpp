#pragma once
// LEDs on a 74HC595-style chain: data, clock (shift on the rising edge),
// latch (storage register on the rising edge), optional output enable.
//
// stage() shifts the whole chain, the bit of the highest position first (bit
// 0, the first register's Q0, is shifted last); the LEDs keep showing the
// storage register meanwhile. commit() pulses the latch, so the LEDs change
// together at the latch edge, on time, however long the chain. The output-enable line is held
// inactive from the request until the chain has been cleared and latched once,
// so whatever the registers powered up with never reaches the LEDs; on
// destruction the chain is cleared and OE released again.

#include "lightstage/firmware/led_driver.hpp"

#include <map>
#include <vector>

namespace lightstage::firmware {

class ShiftRegisterLedDriver final : public LedDriver {
 public:
  ShiftRegisterLedDriver(const Rig& rig, const ShiftRegisterChain& chain, gpio::Chip& chip,
                         const gpio::ChipInfo& info, Clock& clock);
  ~ShiftRegisterLedDriver() override;
  ShiftRegisterLedDriver(const ShiftRegisterLedDriver&) = delete;
  ShiftRegisterLedDriver& operator=(const ShiftRegisterLedDriver&) = delete;

  void stage(std::span<const int> led_ids) override;
  std::int64_t commit(std::int64_t t_ns) override;
  bool carries(int led_id) const override { return bit_of_.contains(led_id); }
  std::string describe() const override;

  // Positions of the lines in the output request (values are data, clock, latch[, OE]).
  static constexpr std::size_t kData = 0, kClock = 1, kLatch = 2, kOutputEnable = 3;

 private:
  void shift(const std::vector<int>& bits, std::int64_t& t_ns);
  // Returns the time of the latch edge.
  std::int64_t latch(std::int64_t t_ns);
  std::int64_t shift_and_latch(const std::vector<int>& bits, std::int64_t t_ns);
  // Sets the lines no sooner than half a clock period after the previous change.
  void step(std::int64_t& t_ns);

  std::string chain_name_;
  int length_;
  std::int64_t half_period_ns_;
  bool has_output_enable_;
  Clock& clock_;
  std::map<int, int> bit_of_;  // LED id -> chain bit
  std::unique_ptr<gpio::OutputLines> lines_;
  std::vector<int> values_;
  std::int64_t last_change_ns_ = 0;
};

}  // namespace lightstage::firmware
