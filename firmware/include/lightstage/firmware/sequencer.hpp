#pragma once
// The sequencer: runs an uploaded sequence step by step on absolute deadlines
// and reports what actually happened and when.
//
// One step (controller.proto, Step), with its planned times:
//   on      = the step's start              LEDs on (and a stills camera's
//                                           half-press, when the rig has one)
//   trigger = on + settle                   trigger asserted (if `trigger`);
//                                           settle = settle_us, or the rig's
//                                           focus lead when that is longer
//             trigger + pulse (rig)         trigger and half-press released
//   off     = trigger + shutter lag (rig)   LEDs off (open loop), or at the
//             + exposure_us                 strobe's falling edge (closed
//                                           loop, `wait_strobe`)
//   next    = off + gap_us                  the next step's start
// The plan is absolute, computed from the sequence's start (and, after a
// closed-loop step, from the strobe edge that ended it), so time spent working
// between deadlines never accumulates into drift. A late event never shortens
// what the camera needs: the trigger waits at least settle_us after the LEDs
// actually came on, and the LEDs stay on at least exposure_us after the
// trigger actually fired; the dark gap absorbs the delay instead.
//
// The LEDs' next state is staged before its deadline (LedDriver::stage: a
// chain shifts it in while the LEDs keep showing the old one; dark is staged
// once the trigger pulse is over), so each deadline costs one latch.
//
// lateness_ns of a step is the largest (actual - planned) over its deadlines
// (LEDs on, trigger, trigger release, LEDs off; for a closed-loop step the
// LEDs-off deadline is the strobe edge itself), so it measures how late the
// controller acts, never the camera.
//
// Safety: check() refuses up front a sequence that would exceed an LED's
// continuous on-time or its duty over the window (closed-loop steps counted at
// their full strobe timeout); at run time each step is checked again against
// the LEDs' real history, and an LED that reaches its on-time limit is
// switched off at once (outcome SAFETY_LIMIT). A missing strobe edge switches
// the LEDs off at the timeout (STROBE_TIMEOUT). Every way out of run() leaves
// the LEDs dark and the trigger released.

#include "lightstage/common/clock.hpp"
#include "lightstage/common/gpio.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/firmware/led_driver.hpp"
#include "lightstage/firmware/led_safety.hpp"
#include "lightstage/firmware/refusal.hpp"
#include "lightstage/firmware/stop_flag.hpp"
#include "lightstage/firmware/trigger_output.hpp"
#include "lightstage/proto/controller.pb.h"

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <vector>

namespace lightstage::firmware {

class Sequencer {
 public:
  static constexpr std::uint32_t kMaxSteps = 10'000;
  // How far ahead of the controller's clock a run may be scheduled: a host
  // synchronising a start asks for milliseconds, and any bound keeps the
  // step times (start + durations) inside int64 nanoseconds.
  static constexpr std::int64_t kMaxStartAheadNs = 60'000'000'000;
  // How often a wait wakes to look at the stop flag (abort, watchdog, signal).
  static constexpr std::int64_t kStopPollNs = 2'000'000;

  struct Observer {
    std::function<void(const proto::StepEvent&)> on_step;
    // LEDs switched: the step index and the LEDs now lit (empty: dark).
    std::function<void(std::uint32_t step, std::span<const int> leds_on)> on_leds;
  };

  // `strobe` may be null (no strobe input: open loop only). The sequencer
  // records every LED pulse into `safety`.
  Sequencer(const Rig& rig, LedDriver& leds, TriggerOutput& trigger, gpio::EdgeInput* strobe,
            LedSafety& safety, Clock& clock);

  // What a sequence asks, checked on its own: step count, LED ids and levels,
  // closed loop needs a strobe input, on-time and duty limits within the
  // sequence (planned from time 0 with no earlier history).
  std::optional<Refusal> check(const proto::Sequence& sequence) const;
  // The same, for a run starting at `start_ns`, against the LEDs' recent history.
  std::optional<Refusal> check_run(const proto::Sequence& sequence, std::int64_t start_ns) const;

  // Runs `sequence` from `start_ns` (now if earlier) until it ends, a step
  // fails, or `stop` is raised. Never throws; the LEDs are dark on return.
  proto::SequenceDone run(const proto::Sequence& sequence, std::int64_t start_ns, const StopFlag& stop,
                          const Observer& observer);

  // The LEDs a step lights (level > 0), in the step's order.
  static std::vector<int> lit_leds(const proto::Step& step);
  // LEDs on to trigger, in microseconds: settle_us, or longer for the rig's half-press lead.
  double settle_us(const proto::Step& step) const;
  // The longest the step may keep its LEDs lit, in microseconds (the rig's
  // shutter lag included).
  double worst_case_on_us(const proto::Step& step) const;

 private:
  std::optional<Refusal> check_against(const proto::Sequence& sequence, std::int64_t start_ns,
                                       LedSafety safety) const;

  const Rig& rig_;
  LedDriver& leds_;
  TriggerOutput& trigger_;
  gpio::EdgeInput* strobe_;
  LedSafety& safety_;
  Clock& clock_;
};

}  // namespace lightstage::firmware
