#include "lightstage/firmware/sequencer.hpp"

#include "lightstage/common/clock.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/firmware/led_request.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace lightstage::firmware {
namespace {

constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::max();

std::int64_t us_to_ns(double us) { return std::llround(us * 1000.0); }

double strobe_timeout_us(const Rig& rig, const proto::Step& step) {
  if (step.strobe_timeout_us() > 0) return step.strobe_timeout_us();
  return rig.strobe ? rig.strobe->timeout_us : 0;
}

// One run of a sequence: the plan, the step being run and what it has done.
class SequenceRun {
 public:
  SequenceRun(const Rig& rig, const Sequencer& sequencer, LedDriver& leds, TriggerOutput& trigger,
              gpio::EdgeInput* strobe, LedSafety& safety, Clock& clock, const StopFlag& stop,
              const Sequencer::Observer& observer, const proto::Sequence& sequence)
      : rig_(rig),
        sequencer_(sequencer),
        leds_(leds),
        trigger_(trigger),
        strobe_(strobe),
        safety_(safety),
        clock_(clock),
        stop_(stop),
        observer_(observer),
        sequence_(sequence) {}

  proto::SequenceDone execute(std::int64_t start_ns) {
    plan_ns_ = std::max(start_ns, clock_.now_ns());
    try {
      for (int i = 0; i < sequence_.steps_size(); ++i) {
        if (!run_step(static_cast<std::uint32_t>(i), sequence_.steps(i))) break;
        ++steps_ok_;
      }
    } catch (const std::exception& e) {
      // A GPIO failure mid-step: go dark as far as the hardware still lets us.
      emergency_dark();
      end_step(proto::GPIO_ERROR, e.what());
    }
    emergency_dark();
    proto::SequenceDone done;
    done.set_sequence_id(sequence_.id());
    done.set_steps_run(steps_ok_);
    done.set_outcome(outcome_);
    done.set_detail(detail_);
    done.set_max_lateness_ns(max_lateness_ns_);
    return done;
  }

 private:
  enum class Wake { kDeadline, kStopped, kForcedOff, kStrobeFall };

  bool run_step(std::uint32_t index, const proto::Step& step) {
    step_index_ = index;
    event_.Clear();
    event_.set_sequence_id(sequence_.id());
    event_.set_step(index);
    event_.set_tag(step.tag());
    event_.set_planned_start_ns(plan_ns_);
    const std::vector<int> ids = Sequencer::lit_leds(step);
    for (const int id : ids) event_.add_led_ids(static_cast<std::uint32_t>(id));
    const std::int64_t settle_ns = us_to_ns(sequencer_.settle_us(step));

    // Staged ahead (a chain shifts now), so that the deadline costs one latch.
    if (!ids.empty()) {
      leds_.stage(ids);
      dark_staged_ = false;
    }
    if (wait_until(plan_ns_, false) == Wake::kStopped) return end_step(stop_.why(), stop_.detail());

    // The limits again, against what the LEDs really did so far.
    const std::int64_t now = clock_.now_ns();
    const double need_us = sequencer_.worst_case_on_us(step);
    double allowed_us = std::numeric_limits<double>::infinity();
    for (const int id : ids) {
      const double allowed = safety_.allowed_on_us(id, ns_to_us(now));
      if (allowed < need_us) {
        return end_step(
            proto::SAFETY_LIMIT,
            fmt::format("step {}: LED {} may stay on only {:.0f} us now (max_on_us {:.0f}, duty {} "
                        "over {:.0f} us), the step needs {:.0f} us",
                        index, id, allowed, safety_.limits(id).max_on_us, safety_.limits(id).max_duty,
                        safety_.limits(id).duty_window_us, need_us));
      }
      allowed_us = std::min(allowed_us, allowed);
    }
    std::int64_t lit_ns = now;
    if (!ids.empty()) {
      lit_ns = leds_.commit(now);
      lit_ = ids;
      lit_since_ns_ = lit_ns;
      forced_off_ns_ = lit_ns + us_to_ns(allowed_us);
      event_.set_leds_on_ns(lit_ns);
      late(lit_ns, plan_ns_);
      notify_leds();
    }
    if (step.trigger()) trigger_.focus_at(lit_ns);  // half-press for the whole lead

    // Settle, then trigger: never sooner than settle_us after the LEDs came on.
    const std::int64_t trigger_plan_ns = plan_ns_ + settle_ns;
    if (strobe_) strobe_->drain();
    if (const Wake wake = wait_until(std::max(trigger_plan_ns, lit_ns + settle_ns), false);
        wake != Wake::kDeadline) {
      return end_interrupted(wake);
    }
    const std::int64_t exposure_start_ns = clock_.now_ns();
    if (step.trigger()) {
      trigger_.assert_at(exposure_start_ns);
      event_.set_trigger_ns(exposure_start_ns);
      late(exposure_start_ns, trigger_plan_ns);
      trigger_end_plan_ns_ = trigger_plan_ns + trigger_.pulse_ns();
      trigger_end_ns_ = std::max(trigger_end_plan_ns_, exposure_start_ns + trigger_.pulse_ns());
    }
    exposure_start_ns_ = exposure_start_ns;
    stage_dark_pending_ = !lit_.empty();

    // Exposure: a fixed time (open loop) or until the camera says it is done.
    std::int64_t off_plan_ns = 0;
    if (step.wait_strobe()) {
      const double timeout_us = strobe_timeout_us(rig_, step);
      const Wake wake = wait_until(exposure_start_ns + us_to_ns(timeout_us), true);
      if (wake == Wake::kDeadline) {
        return end_step(
            proto::STROBE_TIMEOUT,
            fmt::format("step {}: no strobe falling edge within {:.0f} us of the trigger; LEDs switched "
                        "off at the timeout",
                        index, timeout_us));
      }
      if (wake != Wake::kStrobeFall) return end_interrupted(wake);
      off_plan_ns = event_.strobe_fall_ns();
    } else {
      // A stills camera starts exposing up to its shutter lag after the trigger.
      const std::int64_t exposure_ns =
          us_to_ns(step.exposure_us() + (step.trigger() ? rig_.trigger.shutter_lag_us : 0.0));
      off_plan_ns = trigger_plan_ns + exposure_ns;
      if (const Wake wake = wait_until(std::max(off_plan_ns, exposure_start_ns + exposure_ns), false);
          wake != Wake::kDeadline) {
        return end_interrupted(wake);
      }
    }
    if (!lit_.empty()) {
      leds_off();
      late(event_.leds_off_ns(), off_plan_ns);
    }
    // A trigger pulse longer than the exposure ends within its own step.
    if (trigger_end_ns_ != kNever && wait_until(trigger_end_ns_, false) == Wake::kStopped) {
      return end_step(stop_.why(), stop_.detail());
    }
    if (strobe_ && !step.wait_strobe()) collect_strobe_edges();
    plan_ns_ = off_plan_ns + us_to_ns(step.gap_us());
    emit();
    return true;
  }

  // Sleeps (or waits for strobe edges) until `deadline_ns`, releasing the
  // trigger when its pulse ends, and waking early for a stop request, the
  // LEDs' on-time limit, or (closed loop) the strobe's falling edge.
  Wake wait_until(std::int64_t deadline_ns, bool watch_strobe) {
    for (;;) {
      if (stop_.requested()) return Wake::kStopped;
      const std::int64_t now = clock_.now_ns();
      if (now >= trigger_end_ns_) {
        release_trigger(now);
        continue;
      }
      if (stage_dark_pending_ && trigger_end_ns_ == kNever) {
        // Dark goes into the chain while the LEDs still show this step.
        leds_.stage({});
        stage_dark_pending_ = false;
        dark_staged_ = true;
        continue;
      }
      if (now >= forced_off_ns_ && forced_off_ns_ < deadline_ns) return Wake::kForcedOff;
      if (now >= deadline_ns) {
        // Woken late, the strobe may have fallen in time with its edge still queued.
        if (watch_strobe && strobe_fell_by(deadline_ns)) return Wake::kStrobeFall;
        return Wake::kDeadline;
      }
      const std::int64_t next =
          std::min({deadline_ns, forced_off_ns_, trigger_end_ns_, now + Sequencer::kStopPollNs});
      if (!watch_strobe) {
        clock_.sleep_until(next);
        continue;
      }
      const auto edge = strobe_->wait_until(next);
      if (edge && note_strobe_edge(*edge)) return Wake::kStrobeFall;
    }
  }

  // Records an edge of this exposure (its first rise, its fall; earlier edges are ignored):
  // true for a fall.
  bool note_strobe_edge(const gpio::EdgeEvent& edge) {
    if (edge.t_ns < exposure_start_ns_) return false;
    if (edge.rising) {
      if (event_.strobe_rise_ns() == 0) event_.set_strobe_rise_ns(edge.t_ns);
      return false;
    }
    event_.set_strobe_fall_ns(edge.t_ns);
    return true;
  }

  // Whether the edges that happened by now hold a fall at or before `deadline_ns`.
  bool strobe_fell_by(std::int64_t deadline_ns) {
    strobe_->catch_up();
    while (const auto edge = strobe_->wait_until(0)) {
      if (edge->t_ns > deadline_ns) return false;
      if (note_strobe_edge(*edge)) return true;
    }
    return false;
  }

  void collect_strobe_edges() {
    while (const auto edge = strobe_->wait_until(0)) note_strobe_edge(*edge);
  }

  void release_trigger(std::int64_t now) {
    trigger_.release_at(now);
    event_.set_trigger_end_ns(now);
    late(now, trigger_end_plan_ns_);
    trigger_end_ns_ = kNever;
  }

  void leds_off() {
    const std::int64_t now = clock_.now_ns();
    const std::int64_t off_ns = dark_staged_ ? leds_.commit(now) : leds_.all_off(now);
    dark_staged_ = false;
    stage_dark_pending_ = false;
    event_.set_leds_off_ns(off_ns);
    for (const int id : lit_) safety_.record(id, ns_to_us(lit_since_ns_), ns_to_us(off_ns));
    lit_.clear();
    forced_off_ns_ = kNever;
    notify_leds();
  }

  bool end_interrupted(Wake wake) {
    if (wake == Wake::kForcedOff) {
      return end_step(
          proto::SAFETY_LIMIT,
          fmt::format("step {}: LEDs reached their on-time limit after {:.0f} us and were switched off",
                      step_index_, ns_to_us(clock_.now_ns() - lit_since_ns_)));
    }
    return end_step(stop_.why(), stop_.detail());
  }

  // Ends the sequence in this step: dark at once, then report.
  bool end_step(proto::Outcome outcome, const std::string& detail) {
    if (!lit_.empty()) leds_off();
    if (trigger_end_ns_ != kNever) release_trigger(clock_.now_ns());
    event_.set_outcome(outcome);
    event_.set_detail(detail);
    outcome_ = outcome;
    detail_ = detail;
    emit();
    return false;
  }

  void emergency_dark() {
    dark_staged_ = false;
    stage_dark_pending_ = false;
    try {
      if (!lit_.empty()) {
        lit_.clear();
        leds_.all_off(clock_.now_ns());
        notify_leds();
      }
    } catch (const std::exception& e) {
      logger("firmware")->critical("could not switch the LEDs off: {}", e.what());
    }
    try {
      if (trigger_.asserted()) trigger_.release_at(clock_.now_ns());
      trigger_end_ns_ = kNever;
    } catch (const std::exception& e) {
      logger("firmware")->error("could not release the trigger: {}", e.what());
    }
  }

  void late(std::int64_t actual_ns, std::int64_t planned_ns) {
    event_.set_lateness_ns(std::max(event_.lateness_ns(), actual_ns - planned_ns));
  }

  void emit() {
    max_lateness_ns_ = std::max(max_lateness_ns_, event_.lateness_ns());
    if (!observer_.on_step) return;
    try {
      observer_.on_step(event_);
    } catch (const std::exception& e) {
      logger("firmware")->warn("step event not delivered: {}", e.what());
    }
  }

  void notify_leds() {
    if (!observer_.on_leds) return;
    try {
      observer_.on_leds(step_index_, lit_);
    } catch (const std::exception& e) {
      logger("firmware")->warn("LED state not delivered: {}", e.what());
    }
  }

  const Rig& rig_;
  const Sequencer& sequencer_;
  LedDriver& leds_;
  TriggerOutput& trigger_;
  gpio::EdgeInput* strobe_;
  LedSafety& safety_;
  Clock& clock_;
  const StopFlag& stop_;
  const Sequencer::Observer& observer_;
  const proto::Sequence& sequence_;

  std::int64_t plan_ns_ = 0;  // the current step's planned start
  std::uint32_t step_index_ = 0;
  proto::StepEvent event_;
  std::vector<int> lit_;
  std::int64_t lit_since_ns_ = 0;
  std::int64_t forced_off_ns_ = kNever;
  std::int64_t trigger_end_ns_ = kNever;
  std::int64_t trigger_end_plan_ns_ = 0;
  std::int64_t exposure_start_ns_ = 0;
  bool stage_dark_pending_ = false;  // stage dark once the trigger pulse is over
  bool dark_staged_ = false;         // the driver holds dark, ready to commit
  std::uint32_t steps_ok_ = 0;
  proto::Outcome outcome_ = proto::OK;
  std::string detail_;
  std::int64_t max_lateness_ns_ = 0;
};

}  // namespace

Sequencer::Sequencer(const Rig& rig, LedDriver& leds, TriggerOutput& trigger, gpio::EdgeInput* strobe,
                     LedSafety& safety, Clock& clock)
    : rig_(rig), leds_(leds), trigger_(trigger), strobe_(strobe), safety_(safety), clock_(clock) {}

std::vector<int> Sequencer::lit_leds(const proto::Step& step) {
  std::vector<int> ids;
  for (const auto& led : step.leds()) {
    if (led.level() > 0) ids.push_back(static_cast<int>(led.led_id()));
  }
  return ids;
}

double Sequencer::settle_us(const proto::Step& step) const {
  return step.trigger() ? rig_.trigger.lead_us(step.settle_us()) : step.settle_us();
}

double Sequencer::worst_case_on_us(const proto::Step& step) const {
  if (step.wait_strobe()) return settle_us(step) + strobe_timeout_us(rig_, step);
  return settle_us(step) + static_cast<double>(step.exposure_us()) +
         (step.trigger() ? rig_.trigger.shutter_lag_us : 0.0);
}

std::optional<Refusal> Sequencer::check(const proto::Sequence& sequence) const {
  return check_against(sequence, 0, LedSafety(rig_));
}

std::optional<Refusal> Sequencer::check_run(const proto::Sequence& sequence, std::int64_t start_ns) const {
  const std::int64_t now_ns = clock_.now_ns();
  if (start_ns > now_ns && start_ns - now_ns > kMaxStartAheadNs) {
    return Refusal{
        proto::Error::BAD_REQUEST,
        fmt::format("sequence {}: start_ns {} is {:.0f} s ahead of the controller's clock (at most {} s)",
                    sequence.id(), start_ns, static_cast<double>(start_ns - now_ns) * 1e-9,
                    kMaxStartAheadNs / 1'000'000'000)};
  }
  return check_against(sequence, std::max(start_ns, now_ns), safety_);
}

std::optional<Refusal> Sequencer::check_against(const proto::Sequence& sequence, std::int64_t start_ns,
                                                LedSafety safety) const {
  const auto bad = [&](std::string message) {
    return Refusal{proto::Error::BAD_REQUEST, fmt::format("sequence {}: {}", sequence.id(), message)};
  };
  if (sequence.steps_size() == 0) return bad("has no steps");
  if (static_cast<std::uint32_t>(sequence.steps_size()) > kMaxSteps) {
    return bad(fmt::format("{} steps, at most {} allowed", sequence.steps_size(), kMaxSteps));
  }
  std::int64_t t_ns = start_ns;
  for (int i = 0; i < sequence.steps_size(); ++i) {
    const proto::Step& step = sequence.steps(i);
    if (auto problem = led_levels_problem(rig_, step.leds(), i)) return bad(*problem);
    if (step.wait_strobe() && !strobe_) {
      return bad(fmt::format("step {} waits for the strobe, but rig '{}' has no strobe input", i, rig_.name));
    }
    const double on_us = worst_case_on_us(step);
    for (const int id : lit_leds(step)) {
      const SafetyVerdict verdict = safety.check(id, ns_to_us(t_ns), on_us);
      if (!verdict.allowed) {
        return Refusal{proto::Error::SAFETY_LIMIT,
                       fmt::format("sequence {}: step {}{}: {}", sequence.id(), i,
                                   step.wait_strobe() ? " (closed loop, counted at its strobe timeout)" : "",
                                   verdict.reason)};
      }
      safety.record(id, ns_to_us(t_ns), ns_to_us(t_ns) + on_us);
    }
    t_ns += us_to_ns(on_us + step.gap_us());
  }
  return std::nullopt;
}

proto::SequenceDone Sequencer::run(const proto::Sequence& sequence, std::int64_t start_ns,
                                   const StopFlag& stop, const Observer& observer) {
  SequenceRun run(rig_, *this, leds_, trigger_, strobe_, safety_, clock_, stop, observer, sequence);
  return run.execute(start_ns);
}

}  // namespace lightstage::firmware
