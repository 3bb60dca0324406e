// The audit log: one JSON line per action, appended, kept across restarts.
#include "lightstage/station/audit_log.hpp"

#include "lightstage/common/error.hpp"

#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace lightstage::station {
namespace {

std::vector<nlohmann::json> lines_of(const std::filesystem::path& file) {
  std::vector<nlohmann::json> lines;
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);) lines.push_back(nlohmann::json::parse(line));
  return lines;
}

TEST(AuditLog, EveryActionIsOneLineAndALaterStationAppends) {
  const auto file = testing::scratch_dir() / "data" / "audit.log";
  {
    AuditLog log(file);
    log.record({"tab-a", "Ann", "127.0.0.1", "capture.start", {{"name", "coin"}}, "ok"});
    log.record({"tab-b", "", "10.0.0.2", "leds.set", nlohmann::json::object(), "refused: not the operator"});
  }
  AuditLog again(file);
  again.record({"", "station", "", "dark", {{"why", "\xff odd bytes"}}, "ok"});
  const auto lines = lines_of(file);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0]["action"], "capture.start");
  EXPECT_EQ(lines[0]["name"], "Ann");
  EXPECT_EQ(lines[0]["details"]["name"], "coin");
  EXPECT_EQ(lines[1]["outcome"], "refused: not the operator");
  EXPECT_EQ(lines[1]["address"], "10.0.0.2");
  EXPECT_EQ(lines[2]["action"], "dark");
  const std::string time = lines[0]["time"];
  EXPECT_EQ(time.size(), 24u) << time;
  EXPECT_EQ(time.back(), 'Z');
}

TEST(AuditLog, AnUnwritableLogIsRefusedNamingIt) {
  const auto dir = testing::scratch_dir() / "log-is-a-folder";
  std::filesystem::create_directories(dir);
  try {
    AuditLog log(dir);
    FAIL() << "opened a folder as the audit log";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(dir.string()), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lightstage::station
