#include "lightstage/firmware/controller.hpp"

#include "lightstage/common/clock.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/firmware/led_request.hpp"
#include "lightstage/firmware/realtime.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

namespace lightstage::firmware {
namespace {

bool is_safety_stop(proto::Outcome why) { return why != proto::OK && why != proto::ABORTED_BY_HOST; }

}  // namespace

Controller::Controller(const Rig& rig, DomeIo io, Clock& clock, ControllerOptions options)
    : rig_(rig),
      io_(std::move(io)),
      clock_(clock),
      options_(options),
      safety_(rig),
      sequencer_(rig, *io_.leds, *io_.trigger, io_.strobe.get(), safety_, clock) {
  darken_now();
  if (options_.realtime) {
    const RealtimeResult permitted = realtime_permitted(options_.realtime_priority);
    realtime_ = permitted.ok && options_.memory_locked;
    if (!permitted.ok) {
      logger("firmware")
          ->warn(
              "no real-time scheduling for the sequencer: {}; deadlines may be missed by "
              "milliseconds on a loaded machine",
              permitted.problem);
    }
  }
  status_.set_state(proto::Status::IDLE);
}

Controller::~Controller() {
  stop_job(proto::SHUTDOWN, "controller shut down");
  darken_now();
}

void Controller::set_sink(Sink sink) {
  const std::lock_guard lock(sink_mutex_);
  sink_ = std::move(sink);
}

void Controller::send(const proto::ControllerMessage& message) {
  const std::lock_guard lock(sink_mutex_);
  if (!sink_) return;
  try {
    sink_(message);
  } catch (const std::exception& e) {
    logger("firmware")->warn("unsolicited message not delivered: {}", e.what());
  }
}

void Controller::note_leds(std::uint32_t step, std::span<const int> leds_on) {
  const std::lock_guard lock(status_mutex_);
  status_.set_step(step);
  status_.clear_leds_on();
  for (const int id : leds_on) status_.add_leds_on(static_cast<std::uint32_t>(id));
}

void Controller::fault(proto::Outcome why, const std::string& detail, const std::vector<int>& leds) {
  {
    const std::lock_guard lock(status_mutex_);
    status_.set_state(proto::Status::FAULT);
    if (!gpio_failure_) status_.set_last_fault(detail);  // the backend's loss explains the rest
  }
  logger("firmware")->warn("fault ({}): {}", proto::Outcome_Name(why), detail);
  proto::ControllerMessage message;
  proto::Fault& body = *message.mutable_fault();
  body.set_outcome(why);
  body.set_detail(detail);
  for (const int id : leds) body.add_led_ids(static_cast<std::uint32_t>(id));
  body.set_t_ns(clock_.now_ns());
  send(message);
}

void Controller::clear_fault() {
  const std::lock_guard lock(status_mutex_);
  if (status_.state() == proto::Status::FAULT && !gpio_failure_) status_.set_state(proto::Status::IDLE);
}

void Controller::note_gpio_failure(const std::string& what) {
  const std::lock_guard lock(status_mutex_);
  if (gpio_failure_) return;  // the first failure is the one that explains
  gpio_failure_ = what;
  status_.set_state(proto::Status::FAULT);
  status_.set_last_fault(fmt::format("GPIO backend lost: {}", what));
}

std::optional<std::string> Controller::gpio_failure() const {
  const std::lock_guard lock(status_mutex_);
  return gpio_failure_;
}

std::optional<Refusal> Controller::refuse_if_gpio_failed() const {
  if (const auto failure = gpio_failure()) {
    return Refusal{proto::Error::GPIO_ERROR,
                   fmt::format("the GPIO backend failed ({}); lightstage-domed is shutting down", *failure)};
  }
  return std::nullopt;
}

void Controller::forget_sequences() {
  sequences_.clear();
  sequence_bytes_ = 0;
}

proto::Status Controller::status() const {
  const std::lock_guard lock(status_mutex_);
  proto::Status status = status_;
  status.set_clock_ns(clock_.now_ns());
  return status;
}

bool Controller::active() const {
  if (sequence_running_) return true;
  const std::lock_guard lock(status_mutex_);
  return status_.leds_on_size() > 0;
}

void Controller::join_if_finished() {
  if (worker_.joinable() && job_finished_) worker_.join();
}

void Controller::stop_job(proto::Outcome why, const std::string& detail) {
  if (!worker_.joinable()) return;
  stop_.request(why, detail);
  worker_.join();
}

void Controller::start_job(std::function<void()> job) {
  stop_.reset();
  job_finished_ = false;
  worker_ = std::thread([this, job = std::move(job)] {
    if (options_.realtime) {
      if (const RealtimeResult rt = make_this_thread_realtime(options_.realtime_priority); !rt.ok) {
        logger("firmware")->debug("worker not real-time: {}", rt.problem);
      }
    }
    job();
    job_finished_ = true;
  });
}

std::vector<int> Controller::darken_now() {
  std::vector<int> were_lit;
  const std::int64_t now = clock_.now_ns();
  std::int64_t off_ns = now;
  try {
    off_ns = io_.leds->all_off(now);
  } catch (const std::exception& e) {
    logger("firmware")->critical("could not switch the LEDs off: {}", e.what());
    note_gpio_failure(fmt::format("switching the LEDs off: {}", e.what()));
  }
  try {
    if (io_.trigger->asserted()) io_.trigger->release_at(clock_.now_ns());
  } catch (const std::exception& e) {
    logger("firmware")->error("could not release the trigger: {}", e.what());
  }
  for (const auto& [id, held] : held_) {
    safety_.record(id, ns_to_us(held.on_ns), ns_to_us(off_ns));
    were_lit.push_back(id);
  }
  held_.clear();
  note_leds(status().step(), {});
  return were_lit;
}

std::optional<Refusal> Controller::set_leds(const proto::SetLeds& request) {
  join_if_finished();
  if (auto refusal = refuse_if_gpio_failed()) return refusal;
  if (sequence_running_) {
    return Refusal{proto::Error::BUSY,
                   fmt::format("sequence {} is running; abort it first", status().sequence_id())};
  }
  if (auto problem = led_levels_problem(rig_, request.leds())) {
    return Refusal{proto::Error::BAD_REQUEST, *problem};
  }
  stop_job(proto::OK, "superseded by SetLeds");  // the hold; LEDs stay as they are for now

  std::vector<int> wanted;
  for (const auto& led : request.leds()) {
    if (led.level() > 0) wanted.push_back(static_cast<int>(led.led_id()));
  }
  const std::int64_t now = clock_.now_ns();
  std::map<int, double> allowed_us;  // newly lit LEDs and their budget
  for (const int id : wanted) {
    if (held_.contains(id)) continue;  // stays lit: its deadline stands
    const double allowed = safety_.allowed_on_us(id, ns_to_us(now));
    if (allowed < options_.min_hold_us) {
      if (!held_.empty()) start_hold();  // the previous state stands
      const LedLimits& limits = safety_.limits(id);
      return Refusal{
          proto::Error::SAFETY_LIMIT,
          fmt::format("LED {}: its duty budget is spent ({:.0f} us left; max_duty {} over {:.0f} us)", id,
                      allowed, limits.max_duty, limits.duty_window_us)};
    }
    allowed_us[id] = allowed;
  }
  std::int64_t changed_ns = now;
  try {
    changed_ns = io_.leds->show(wanted, now);
  } catch (const std::exception& e) {
    note_gpio_failure(fmt::format("setting LEDs: {}", e.what()));
    const std::vector<int> were_lit = darken_now();
    fault(proto::GPIO_ERROR, fmt::format("setting LEDs failed: {}", e.what()), were_lit);
    return Refusal{proto::Error::GPIO_ERROR, e.what()};
  }
  std::map<int, HeldLed> next;
  for (const int id : wanted) {
    if (const auto it = held_.find(id); it != held_.end()) {
      next[id] = it->second;
    } else {
      const double margin_us = std::min(options_.cutoff_margin_us, allowed_us[id] / 2);
      next[id] = {changed_ns, changed_ns + std::llround((allowed_us[id] - margin_us) * 1000.0)};
    }
  }
  for (const auto& [id, held] : held_) {
    if (!next.contains(id)) safety_.record(id, ns_to_us(held.on_ns), ns_to_us(changed_ns));
  }
  held_ = std::move(next);
  note_leds(0, wanted);
  if (!held_.empty()) start_hold();
  return std::nullopt;
}

void Controller::start_hold() {
  start_job([this] { hold_job(); });
}

void Controller::hold_job() {
  try {
    while (!held_.empty()) {
      std::int64_t deadline = held_.begin()->second.off_deadline_ns;
      for (const auto& [id, held] : held_) deadline = std::min(deadline, held.off_deadline_ns);
      for (std::int64_t now = clock_.now_ns(); now < deadline; now = clock_.now_ns()) {
        if (stop_.requested()) return;
        clock_.sleep_until(std::min(deadline, now + Sequencer::kStopPollNs));
      }
      if (stop_.requested()) return;
      // The limit is reached: those LEDs go dark, the rest stay lit.
      std::vector<int> expired;
      std::vector<int> remaining;
      for (const auto& [id, held] : held_)
        (held.off_deadline_ns <= deadline ? expired : remaining).push_back(id);
      const std::int64_t off_ns = io_.leds->show(remaining, clock_.now_ns());
      std::string detail;
      for (const int id : expired) {
        const HeldLed held = held_[id];
        safety_.record(id, ns_to_us(held.on_ns), ns_to_us(off_ns));
        held_.erase(id);
        const LedLimits& limits = safety_.limits(id);
        detail += fmt::format(
            "{}LED {} switched off after {:.0f} us (max_on_us {:.0f}, max_duty {} over {:.0f} us)",
            detail.empty() ? "" : "; ", id, ns_to_us(off_ns - held.on_ns), limits.max_on_us, limits.max_duty,
            limits.duty_window_us);
      }
      note_leds(0, remaining);
      fault(proto::SAFETY_LIMIT, detail, expired);
    }
  } catch (const std::exception& e) {
    note_gpio_failure(fmt::format("static LEDs: {}", e.what()));
    const std::vector<int> were_lit = darken_now();
    fault(proto::GPIO_ERROR, fmt::format("static LEDs: {}", e.what()), were_lit);
  }
}

std::optional<Refusal> Controller::upload(const proto::Sequence& sequence) {
  if (auto refusal = refuse_if_gpio_failed()) return refusal;
  if (auto refusal = sequencer_.check(sequence)) return refusal;
  const auto replaced = sequences_.find(sequence.id());
  if (replaced == sequences_.end() && sequences_.size() >= options_.max_sequences) {
    return Refusal{proto::Error::BAD_REQUEST,
                   fmt::format("sequence {}: the controller holds at most {} sequences; reuse an id",
                               sequence.id(), options_.max_sequences)};
  }
  const std::size_t bytes = sequence.ByteSizeLong();
  const std::size_t freed = replaced == sequences_.end() ? 0 : replaced->second.ByteSizeLong();
  if (sequence_bytes_ - freed + bytes > options_.max_sequence_bytes) {
    return Refusal{
        proto::Error::BAD_REQUEST,
        fmt::format("sequence {}: {} bytes would make the stored sequences {} bytes, over the "
                    "controller's {} byte limit; reuse an id",
                    sequence.id(), bytes, sequence_bytes_ - freed + bytes, options_.max_sequence_bytes)};
  }
  if (sequence_running_ && status().sequence_id() == sequence.id()) {
    return Refusal{proto::Error::BUSY,
                   fmt::format("sequence {} is running; abort it before replacing it", sequence.id())};
  }
  sequences_[sequence.id()] = sequence;
  sequence_bytes_ = sequence_bytes_ - freed + bytes;
  return std::nullopt;
}

std::optional<Refusal> Controller::run(std::uint32_t sequence_id, std::int64_t start_ns,
                                       const std::function<void()>& accepted) {
  join_if_finished();
  if (auto refusal = refuse_if_gpio_failed()) return refusal;
  if (sequence_running_) {
    return Refusal{proto::Error::BUSY, fmt::format("sequence {} is running", status().sequence_id())};
  }
  const auto it = sequences_.find(sequence_id);
  if (it == sequences_.end()) {
    return Refusal{proto::Error::NO_SUCH_SEQUENCE, fmt::format("no sequence {} was uploaded", sequence_id)};
  }
  // A sequence owns every LED: static ones go dark first.
  stop_job(proto::OK, "superseded by RunSequence");
  darken_now();
  if (auto refusal = sequencer_.check_run(it->second, start_ns)) return refusal;
  {
    const std::lock_guard lock(status_mutex_);
    status_.set_state(proto::Status::RUNNING);
    status_.set_sequence_id(sequence_id);
    status_.set_step(0);
  }
  sequence_running_ = true;
  try {
    if (accepted) accepted();
  } catch (...) {
    sequence_running_ = false;  // the reply could not go out: do not start
    const std::lock_guard lock(status_mutex_);
    status_.set_state(proto::Status::IDLE);
    throw;
  }
  start_job([this, sequence = it->second, start_ns] {
    Sequencer::Observer observer;
    observer.on_step = [this](const proto::StepEvent& event) {
      proto::ControllerMessage message;
      *message.mutable_step_event() = event;
      send(message);
    };
    observer.on_leds = [this](std::uint32_t step, std::span<const int> leds_on) { note_leds(step, leds_on); };
    const proto::SequenceDone done = sequencer_.run(sequence, start_ns, stop_, observer);
    {
      const std::lock_guard lock(status_mutex_);
      status_.set_state(is_safety_stop(done.outcome()) ? proto::Status::FAULT : proto::Status::IDLE);
      if (done.outcome() != proto::OK) status_.set_last_fault(done.detail());
    }
    if (done.outcome() == proto::GPIO_ERROR) note_gpio_failure(fmt::format("sequence: {}", done.detail()));
    logger("firmware")
        ->info("sequence {} done: {} of {} steps, {}, max lateness {} us{}{}", done.sequence_id(),
               done.steps_run(), sequence.steps_size(), proto::Outcome_Name(done.outcome()),
               done.max_lateness_ns() / 1000, done.detail().empty() ? "" : ": ", done.detail());
    sequence_running_ = false;
    proto::ControllerMessage message;
    *message.mutable_sequence_done() = done;
    send(message);
  });
  return std::nullopt;
}

void Controller::stop(proto::Outcome why, const std::string& detail) {
  const bool was_running = sequence_running_;
  stop_job(why, detail);
  const std::vector<int> were_lit = darken_now();
  if (!were_lit.empty() && why != proto::ABORTED_BY_HOST) {
    fault(why, fmt::format("{}: LEDs {} switched off", detail, fmt::join(were_lit, ", ")), were_lit);
  } else if (was_running && is_safety_stop(why)) {
    const std::lock_guard lock(status_mutex_);
    status_.set_state(proto::Status::FAULT);
    if (!gpio_failure_) status_.set_last_fault(detail);
  }
}

}  // namespace lightstage::firmware
