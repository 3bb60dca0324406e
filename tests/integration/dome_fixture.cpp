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

SimulatedDome::SimulatedDome(DomeOptions options) : options_(std::move(options)) {
  if (options_.rig.empty()) options_.rig = source_dir() / "hw/rigs/sim-dome.yaml";
  dir_ = scratch_dir();
  sim_socket_ = socket_dir() / (std::to_string(reinterpret_cast<std::uintptr_t>(this)) + "-sim.sock");
  controller_socket_ =
      socket_dir() / (std::to_string(reinterpret_cast<std::uintptr_t>(this)) + "-domed.sock");
  camera_socket_ = socket_dir() / (std::to_string(reinterpret_cast<std::uintptr_t>(this)) + "-camera.sock");
  timeline_file_ = dir_ / "timeline.jsonl";

  std::vector<std::string> sim_args = {"--rig",      options_.rig.string(),
                                       "--listen",   "unix:" + sim_socket_.string(),
                                       "--timeline", timeline_file_.string()};
  if (options_.camera) {
    sim_args.push_back("--camera");
    sim_args.push_back("unix:" + camera_socket_.string());
  }
  sim_args.insert(sim_args.end(), options_.sim_args.begin(), options_.sim_args.end());
  sim_ = std::make_unique<ChildProcess>(bin_dir() / "lightstage-sim", sim_args, dir_ / "sim.log");
  if (!sim_->wait_for_output("listening on", kStartTimeout)) {
    throw std::runtime_error("lightstage-sim did not start:\n" + sim_->output());
  }
  start_firmware();
}

void SimulatedDome::start_firmware() {
  std::vector<std::string> fw_args = {
      "--rig", options_.rig.string(), "--gpio", "sim:" + sim_socket_.string(), "--listen", controller_uri()};
  fw_args.insert(fw_args.end(), options_.firmware_args.begin(), options_.firmware_args.end());
  firmware_.reset();
  firmware_ = std::make_unique<ChildProcess>(bin_dir() / "lightstage-domed", fw_args,
                                             dir_ / fmt::format("domed-{}.log", ++firmware_starts_));
  if (!firmware_->wait_for_output("listening on", kStartTimeout)) {
    throw std::runtime_error("lightstage-domed did not start:\n" + firmware_->output() + "\nsim:\n" +
                             sim_->output());
  }
}

void SimulatedDome::restart_firmware() { start_firmware(); }

SimulatedDome::~SimulatedDome() {
  if (::testing::Test::HasFailure()) std::fprintf(stderr, "%s\n", logs().c_str());
  firmware_.reset();
  sim_.reset();
}

std::string SimulatedDome::logs() const {
  return "--- lightstage-domed log ---\n" + (firmware_ ? firmware_->output() : "") +
         "--- lightstage-sim log ---\n" + (sim_ ? sim_->output() : "");
}

std::unique_ptr<ControllerClient> SimulatedDome::connect(ControllerClientOptions options) const {
  return std::make_unique<ControllerClient>(connect_socket_link(controller_uri(), std::chrono::seconds(5)),
                                            std::move(options));
}

Timeline SimulatedDome::stop_and_read_timeline() {
  firmware_->signal(SIGTERM);
  const auto fw_exit = firmware_->wait(std::chrono::seconds(10));
  EXPECT_EQ(fw_exit, std::optional<int>(0)) << "lightstage-domed should exit cleanly on SIGTERM";
  sim_->signal(SIGTERM);
  EXPECT_EQ(sim_->wait(std::chrono::seconds(10)), std::optional<int>(0));
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
