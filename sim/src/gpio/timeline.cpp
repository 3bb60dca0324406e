#include "lightstage/sim/gpio/timeline.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cerrno>
#include <cstring>

namespace lightstage::sim::gpio {

std::string to_json_line(const TimelineEntry& entry) {
  // nlohmann::json for the string escaping; the key order is fixed by hand so
  // the file reads the same way as the issue's example.
  std::string line = fmt::format(R"({{"t_ns":{},"line":{},"value":{})", entry.t_ns,
                                 nlohmann::json(entry.line).dump(), entry.value);
  if (entry.led >= 0) line += fmt::format(R"(,"led":{})", entry.led);
  if (!entry.via.empty()) line += fmt::format(R"(,"via":{})", nlohmann::json(entry.via).dump());
  line += "}";
  return line;
}

JsonLinesTimelineFile::JsonLinesTimelineFile(const std::filesystem::path& path)
    : path_(path), file_(std::fopen(path.c_str(), "a")) {
  if (!file_) fail("{}: cannot open the timeline for appending: {}", path.string(), std::strerror(errno));
}

JsonLinesTimelineFile::~JsonLinesTimelineFile() { std::fclose(file_); }

void JsonLinesTimelineFile::record(std::span<const TimelineEntry> entries) {
  if (entries.empty()) return;
  std::string text;
  for (const auto& entry : entries) {
    text += to_json_line(entry);
    text += '\n';
  }
  // One write and a flush per batch: a killed sim loses at most the batch in flight.
  if (std::fwrite(text.data(), 1, text.size(), file_) != text.size() || std::fflush(file_) != 0) {
    logger("sim")->error("{}: cannot write the timeline: {}", path_.string(), std::strerror(errno));
  }
}

}  // namespace lightstage::sim::gpio
