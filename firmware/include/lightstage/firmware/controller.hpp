#pragma once
// The dome controller's state machine, below the protocol: static LEDs
// (SetLeds), uploaded sequences, one job at a time on a worker thread (a
// sequence run, or the hold that switches static LEDs off at their on-time
// limit), and the stop path that darkens the dome.
//
// Threading: every public method is called from one thread (the protocol
// server's); the worker reports through the sink, which may be called from
// the worker thread. The LEDs belong to the worker while a job runs and to
// the caller otherwise; stop() hands them back by joining the worker.
//
// Safety: the LEDs are dark when the controller is built and destroyed, after
// stop(), and after any GPIO error. A static LED stays lit at most as long as
// its on-time limit and its remaining duty budget allow; then the worker
// switches it off and reports a Fault.

#include "lightstage/common/clock.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/firmware/dome_io.hpp"
#include "lightstage/firmware/led_safety.hpp"
#include "lightstage/firmware/refusal.hpp"
#include "lightstage/firmware/sequencer.hpp"
#include "lightstage/firmware/stop_flag.hpp"
#include "lightstage/proto/controller.pb.h"

#include <atomic>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

namespace lightstage::firmware {

struct ControllerOptions {
  // SCHED_FIFO for the worker thread, at this priority, when permitted.
  bool realtime = false;
  int realtime_priority = 80;
  bool memory_locked = false;  // main() called lock_memory() successfully
  std::size_t max_sequences = 64;
  // Stored sequences together, as serialized: a bound on what hosts can make
  // the controller keep (sequences are also dropped when their host's
  // session ends: forget_sequences()).
  std::size_t max_sequence_bytes = 4u << 20;
  // A static LED needs at least this much on-time budget left to be lit.
  double min_hold_us = 1000;
  // A static LED is switched off this long before its limit (at most half its
  // budget), so that a late wake-up on a loaded machine does not overshoot
  // the limit. 0 here (tests on a virtual clock see the exact limit);
  // lightstage-domed sets it from --cutoff-margin-us.
  double cutoff_margin_us = 0;
};

class Controller {
 public:
  using Sink = std::function<void(const proto::ControllerMessage&)>;

  Controller(const Rig& rig, DomeIo io, Clock& clock, ControllerOptions options = {});
  ~Controller();
  Controller(const Controller&) = delete;
  Controller& operator=(const Controller&) = delete;

  // Where unsolicited messages go (StepEvent, SequenceDone, Fault); an empty
  // sink drops them. The sink must not throw.
  void set_sink(Sink sink);

  // Lights exactly these LEDs (level > 0), every other LED dark.
  std::optional<Refusal> set_leds(const proto::SetLeds& request);
  std::optional<Refusal> upload(const proto::Sequence& sequence);
  // Starts an uploaded sequence at `start_ns` (0 or past: now). Static LEDs
  // go dark first. `accepted` runs just before the sequence starts, so a
  // reply sent there precedes every StepEvent.
  std::optional<Refusal> run(std::uint32_t sequence_id, std::int64_t start_ns,
                             const std::function<void()>& accepted = {});
  // Stops whatever runs and darkens every LED. A running sequence ends with
  // `why` in its SequenceDone; lit static LEDs are reported in a Fault unless
  // the host asked (ABORTED_BY_HOST). Safety stops leave the status at FAULT.
  void stop(proto::Outcome why, const std::string& detail);
  // A new command clears FAULT (not a lost GPIO backend: that stays).
  void clear_fault();
  // Drops every uploaded sequence (the host that sent them is gone).
  void forget_sequences();
  // Why the GPIO backend failed, once it has: from then on every command is
  // refused with GPIO_ERROR, Status stays FAULT, and lightstage-domed exits.
  std::optional<std::string> gpio_failure() const;

  proto::Status status() const;
  // LEDs lit or a sequence running: what the watchdog guards.
  bool active() const;
  bool realtime() const { return realtime_; }
  bool has_strobe() const { return io_.strobe != nullptr; }
  const Rig& rig() const { return rig_; }

 private:
  struct HeldLed {
    std::int64_t on_ns = 0;
    std::int64_t off_deadline_ns = 0;
  };

  void join_if_finished();
  // Stops the job without touching the LEDs (the caller decides what follows).
  void stop_job(proto::Outcome why, const std::string& detail);
  void start_hold();
  void hold_job();
  void start_job(std::function<void()> job);
  // Switches every LED off and records the held ones; never throws.
  std::vector<int> darken_now();
  void send(const proto::ControllerMessage& message);
  void note_leds(std::uint32_t step, std::span<const int> leds_on);
  void fault(proto::Outcome why, const std::string& detail, const std::vector<int>& leds);
  void note_gpio_failure(const std::string& what);
  std::optional<Refusal> refuse_if_gpio_failed() const;

  const Rig& rig_;
  DomeIo io_;
  Clock& clock_;
  ControllerOptions options_;
  LedSafety safety_;
  Sequencer sequencer_;
  bool realtime_ = false;

  std::map<std::uint32_t, proto::Sequence> sequences_;
  std::size_t sequence_bytes_ = 0;  // serialized size of sequences_
  std::map<int, HeldLed> held_;     // static LEDs lit now; see threading above

  std::thread worker_;
  StopFlag stop_;
  std::atomic<bool> sequence_running_{false};
  std::atomic<bool> job_finished_{true};

  mutable std::mutex status_mutex_;
  proto::Status status_;
  std::optional<std::string> gpio_failure_;  // under status_mutex_

  std::mutex sink_mutex_;
  Sink sink_;
};

}  // namespace lightstage::firmware
