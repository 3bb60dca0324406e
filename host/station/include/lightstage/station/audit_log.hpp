#pragma once
// The station's audit log: every action asked of it — who, what, with which
// parameters, and how it ended — one JSON object per line in DATA/audit.log,
// appended and flushed as it happens, so a crash loses nothing written before.

#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>

#include <nlohmann/json.hpp>

namespace lightstage::station {

struct AuditEntry {
  std::string client;   // the browser tab's id ("" = the station itself)
  std::string name;     // the operator's name as they gave it
  std::string address;  // the client's IP address
  std::string action;   // "capture.start", "leds.set", ...
  nlohmann::json details = nlohmann::json::object();
  std::string outcome;  // "ok", "refused: ...", "failed: ..."
};

class AuditLog {
 public:
  // Opens (creates) `file` for appending; throws Error naming it when it cannot.
  explicit AuditLog(std::filesystem::path file);

  void record(const AuditEntry& entry);
  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
  std::mutex mutex_;
  std::ofstream out_;
};

// Now, as UTC with milliseconds: 2026-12-05T11:34:59.123Z.
std::string utc_now_text();

}  // namespace lightstage::station
