#include "lightstage/station/audit_log.hpp"

#include "lightstage/common/error.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>

#include <chrono>
#include <ctime>

namespace lightstage::station {

std::string utc_now_text() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const auto millis =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  return fmt::format("{:%Y-%m-%dT%H:%M:%S}.{:03d}Z", utc, millis);
}

AuditLog::AuditLog(std::filesystem::path file) : file_(std::move(file)) {
  if (file_.has_parent_path()) std::filesystem::create_directories(file_.parent_path());
  out_.open(file_, std::ios::app);
  if (!out_) throw Error(fmt::format("cannot open the audit log {} for appending", file_.string()));
}

void AuditLog::record(const AuditEntry& entry) {
  const nlohmann::json line = {{"time", utc_now_text()},  {"client", entry.client},
                               {"name", entry.name},      {"address", entry.address},
                               {"action", entry.action},  {"details", entry.details},
                               {"outcome", entry.outcome}};
  const std::lock_guard lock(mutex_);
  // Replace, not throw: a client's odd bytes must not cost the record.
  out_ << line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << '\n';
  out_.flush();
}

}  // namespace lightstage::station
