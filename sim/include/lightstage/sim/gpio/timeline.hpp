#pragma once
// The virtual chip's timeline: every change of a line, stamped with the
// firmware's CLOCK_MONOTONIC time (or the emulated camera's, for the strobe),
// plus the LED changes decoded from shift-register chains. Values are "active"
// values as the rig wires the line: 1 = LED lit, trigger asserted, strobe
// (exposure) active, output enable in effect, whatever the electrical level.
//
// As JSON lines (one object per line, appended in the order the sim saw the
// changes; sort by t_ns for a time-ordered view):
//   {"t_ns":123,"line":"LED17","value":1,"led":17}
//   {"t_ns":125,"line":"LED40","value":1,"led":40,"via":"leds"}   (chain bit)
//   {"t_ns":130,"line":"TRIGGER","value":1}

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <span>
#include <string>

namespace lightstage::sim::gpio {

struct TimelineEntry {
  std::int64_t t_ns = 0;
  std::string line;  // the chip's line name, or "LED<id>" for a chain-driven LED
  int value = 0;     // active value: 1 = active
  int led = -1;      // the LED id when the entry is an LED, else -1
  std::string via;   // chain name for LEDs decoded from a shift-register chain
};

std::string to_json_line(const TimelineEntry& entry);  // without the newline

// Receives timeline entries as the chip records them (under the chip's lock:
// keep it quick).
class TimelineSink {
 public:
  virtual ~TimelineSink() = default;
  virtual void record(std::span<const TimelineEntry> entries) = 0;
};

// Appends JSON lines to a file, flushed after every batch so that a reader
// finds everything up to the last change even if the sim is killed.
class JsonLinesTimelineFile final : public TimelineSink {
 public:
  // Throws InputError naming the path when it cannot be opened for appending.
  explicit JsonLinesTimelineFile(const std::filesystem::path& path);
  ~JsonLinesTimelineFile() override;
  JsonLinesTimelineFile(const JsonLinesTimelineFile&) = delete;
  JsonLinesTimelineFile& operator=(const JsonLinesTimelineFile&) = delete;

  void record(std::span<const TimelineEntry> entries) override;

 private:
  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
};

}  // namespace lightstage::sim::gpio
