#include "lightstage/common/log.hpp"

#include "lightstage/common/error.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>

namespace lightstage {

std::shared_ptr<spdlog::logger> logger(const std::string& component) {
  if (auto existing = spdlog::get(component)) return existing;
  auto created = spdlog::stderr_color_mt(component);
  created->set_level(spdlog::get_level());
  created->set_pattern("%^[%l]%$ %n: %v");
  return created;
}

void set_log_level(const std::string& level) {
  const auto parsed = spdlog::level::from_str(level);
  if (parsed == spdlog::level::off && level != "off") fail("--log-level: unknown level '{}'", level);
  spdlog::set_level(parsed);
  spdlog::apply_all([parsed](const std::shared_ptr<spdlog::logger>& l) { l->set_level(parsed); });
}

}  // namespace lightstage
