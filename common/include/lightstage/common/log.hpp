#pragma once
// Logging: one spdlog logger per component ("host", "sim", "firmware", ...),
// all writing to stderr so that stdout stays free for results and --json.

#include <spdlog/spdlog.h>

#include <memory>
#include <string>

namespace lightstage {

// The logger for a component, created on first use.
std::shared_ptr<spdlog::logger> logger(const std::string& component);

// Sets the level of every component's logger: "trace" ... "off".
void set_log_level(const std::string& level);

}  // namespace lightstage
