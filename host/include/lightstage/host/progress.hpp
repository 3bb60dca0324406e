#pragma once
// Progress of a long command on the terminal: "solve  41% 6512/15791 px  ETA 3.1 s"
// (or "integrate  41%  ETA 3.1 s" when the unit is empty: a share, not a count).
// Drawn on stderr only when stderr is a terminal and the command is not
// --quiet or --json, so logs, pipes and CI output stay clean. Thread-safe:
// workers call advance() as they finish items; redraws are rate-limited.

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdio>
#include <mutex>
#include <string>

namespace lightstage {

enum class OutputMode {
  kHuman,  // progress on a terminal, human-readable results
  kQuiet,  // no progress, results only
  kJson,   // no progress, one JSON object on stdout
};

class Progress {
 public:
  // `unit` names the items ("frames", "px"); `total` may be 0 when unknown.
  // An empty `unit` shows only the share done (e.g. total 1000 = per mille).
  Progress(std::string label, std::size_t total, std::string unit, OutputMode mode = OutputMode::kHuman,
           std::FILE* stream = stderr);
  ~Progress();  // finishes the line
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void advance(std::size_t items = 1);
  // Raises the count to `done` (never lowers it): for work that reports where
  // it is rather than what it just finished.
  void advance_to(std::size_t done);
  void set_total(std::size_t total);
  std::size_t done() const { return done_; }
  // Clears the progress line (before printing something else), then finishes.
  void finish();
  bool visible() const { return visible_; }

  // The line that would be drawn (for tests).
  std::string line(std::chrono::steady_clock::duration elapsed) const;

 private:
  void draw(bool force);

  std::string label_, unit_;
  std::atomic<std::size_t> total_, done_{0};
  std::FILE* stream_;
  bool visible_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
  std::mutex mutex_;
};

// True when `stream` is an interactive terminal.
bool is_terminal(std::FILE* stream);

}  // namespace lightstage
