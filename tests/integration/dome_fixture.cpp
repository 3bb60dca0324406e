#include "dome_fixture.hpp"

#include "lightstage/common/socket_link.hpp"
#include "lightstage/testing/paths.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <csignal>
#include <fstream>
#include <limits>
#include <stdexcept>

namespace lightstage::testing {
namespace {

constexpr auto kStartTimeout = std::chrono::seconds(20);

}  // namespace

Timeline Timeline::load(const std::filesystem::path& file) {
  Timeline timeline;
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    const auto j = nlohmann::json::parse(line);
    TimelineEntry e;
    e.t_ns = j.at("t_ns").get<std::int64_t>();
    e.line = j.at("line").get<std::string>();
    e.value = j.at("value").get<int>();
    if (j.contains("via")) e.via = j.at("via").get<std::string>();
    timeline.entries_.push_back(std::move(e));
  }
  // The sim appends in the order it saw changes; lines interleave, so order by time.
  std::stable_sort(timeline.entries_.begin(), timeline.entries_.end(),
                   [](const TimelineEntry& a, const TimelineEntry& b) { return a.t_ns < b.t_ns; });
  return timeline;
}

std::vector<Interval> Timeline::intervals(const std::string& line) const {
  std::vector<Interval> out;
  bool on = false;
  for (const auto& e : entries_) {
    if (e.line != line) continue;
    if (e.value && !on) out.push_back({e.t_ns, std::numeric_limits<std::int64_t>::max()});
    if (!e.value && on) out.back().end_ns = e.t_ns;
    on = e.value != 0;
  }
  return out;
}

std::map<std::string, std::vector<Interval>> Timeline::led_intervals() const {
  std::map<std::string, std::vector<Interval>> out;
  for (const auto& e : entries_) {
    if (e.line.starts_with("LED") && out.count(e.line) == 0) out[e.line] = intervals(e.line);
  }
  return out;
}

std::vector<std::string> Timeline::leds_left_on() const {
  std::vector<std::string> on;
  for (const auto& [line, spans] : led_intervals()) {
    if (!spans.empty() && spans.back().end_ns == std::numeric_limits<std::int64_t>::max()) on.push_back(line);
  }
  return on;
}

namespace {

SimulatedDomeOptions fixture_options(DomeOptions options) {
  SimulatedDomeOptions o;
  o.rig = options.rig.empty() ? source_dir() / "hw/rigs/sim-dome.yaml" : options.rig;
  o.log_dir = scratch_dir();
  // One socket folder per dome: a test may run several side by side.
  static int domes = 0;
  o.socket_dir = socket_dir() / std::to_string(++domes);
  o.program_dir = bin_dir();
  o.sim_args = std::move(options.sim_args);
  o.firmware_args = std::move(options.firmware_args);
  o.camera = options.camera;
  o.timeline = true;
  o.start_timeout = kStartTimeout;
  return o;
}

}  // namespace

SimulatedDome::SimulatedDome(DomeOptions options)
    : lightstage::SimulatedDome(fixture_options(std::move(options))) {}

SimulatedDome::~SimulatedDome() {
  if (::testing::Test::HasFailure()) std::fprintf(stderr, "%s\n", logs().c_str());
}

std::unique_ptr<ControllerClient> SimulatedDome::connect(ControllerClientOptions options) const {
  return std::make_unique<ControllerClient>(connect_socket_link(controller_uri(), std::chrono::seconds(5)),
                                            std::move(options));
}

Timeline SimulatedDome::stop_and_read_timeline() {
  const ExitCodes codes = stop();
  EXPECT_EQ(codes.firmware, 0) << "lightstage-domed should exit cleanly on SIGTERM";
  EXPECT_EQ(codes.sim, 0);
  return read_timeline();
}

std::filesystem::path rig_with_limits(const std::filesystem::path& rig, double max_on_us, double max_duty,
                                      double duty_window_us, const std::filesystem::path& out) {
  YAML::Node root = YAML::LoadFile(rig.string());
  YAML::Node limits;
  limits["max_on_us"] = max_on_us;
  limits["max_duty"] = max_duty;
  limits["duty_window_us"] = duty_window_us;
  if (root["led_defaults"]) root["led_defaults"]["limits"] = limits;
  for (auto led : root["leds"]) {
    if (led["limits"]) led["limits"] = limits;
  }
  std::ofstream(out) << root;
  return out;
}

}  // namespace lightstage::testing
