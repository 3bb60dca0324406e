#include "lightstage/host/progress.hpp"

#include <fmt/format.h>
#include <unistd.h>

namespace lightstage {
namespace {

constexpr auto kRedrawEvery = std::chrono::milliseconds(100);

std::string seconds_text(double s) {
  if (s < 60) return fmt::format("{:.1f} s", s);
  if (s < 3600) return fmt::format("{}m{:02}s", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  return fmt::format("{}h{:02}m", static_cast<int>(s) / 3600, static_cast<int>(s) % 3600 / 60);
}

}  // namespace

bool is_terminal(std::FILE* stream) { return stream != nullptr && ::isatty(::fileno(stream)) == 1; }

Progress::Progress(std::string label, std::size_t total, std::string unit, OutputMode mode, std::FILE* stream)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(total),
      stream_(stream),
      visible_(mode == OutputMode::kHuman && is_terminal(stream)),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

Progress::~Progress() { finish(); }

void Progress::set_total(std::size_t total) { total_ = total; }

void Progress::advance(std::size_t items) {
  done_ += items;
  if (visible_) draw(false);
}

void Progress::advance_to(std::size_t done) {
  std::size_t now = done_;
  while (now < done && !done_.compare_exchange_weak(now, done)) {
  }
  if (visible_) draw(false);
}

std::string Progress::line(std::chrono::steady_clock::duration elapsed) const {
  const double seconds = std::chrono::duration<double>(elapsed).count();
  const std::size_t done = done_, total = total_;
  if (total == 0) return fmt::format("{}  {} {}  {}", label_, done, unit_, seconds_text(seconds));
  const double fraction = std::min(1.0, static_cast<double>(done) / static_cast<double>(total));
  std::string eta = "ETA --";
  // The estimate assumes the rate so far holds; it is shown once there is a rate.
  if (done > 0 && seconds > 0.2) eta = "ETA " + seconds_text(seconds * (1 - fraction) / fraction);
  if (unit_.empty()) return fmt::format("{}  {:3.0f}%  {}", label_, 100 * fraction, eta);
  return fmt::format("{}  {:3.0f}% {}/{} {}  {}", label_, 100 * fraction, done, total, unit_, eta);
}

void Progress::draw(bool force) {
  const std::unique_lock lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock() || finished_) return;  // another thread is drawing: skip this redraw
  const auto now = std::chrono::steady_clock::now();
  if (!force && now - last_draw_ < kRedrawEvery) return;
  last_draw_ = now;
  fmt::print(stream_, "\r\033[K{}", line(now - start_));
  std::fflush(stream_);
}

void Progress::finish() {
  const std::lock_guard lock(mutex_);
  if (finished_) return;
  finished_ = true;
  if (visible_) {
    fmt::print(stream_, "\r\033[K");
    std::fflush(stream_);
  }
}

}  // namespace lightstage
