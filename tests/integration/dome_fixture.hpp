#pragma once
// Starts the simulated dome as separate processes — lightstage-sim (the
// virtual gpiochip) and lightstage-domed (the real firmware on its sim:
// backend) — and reads back the sim's recorded line timeline.

#include "lightstage/host/controller/controller_client.hpp"
#include "lightstage/host/demo/simulated_dome.hpp"

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::testing {

struct TimelineEntry {
  std::int64_t t_ns = 0;
  std::string line;
  int value = 0;
  std::string via;  // chain name for LEDs decoded from a shift register
};

// An interval during which a line was active; end_ns is INT64_MAX if it never went inactive.
struct Interval {
  std::int64_t start_ns = 0, end_ns = 0;
};

class Timeline {
 public:
  static Timeline load(const std::filesystem::path& file);
  const std::vector<TimelineEntry>& entries() const { return entries_; }
  // Active intervals of `line`, in order.
  std::vector<Interval> intervals(const std::string& line) const;
  // Every line whose name starts with "LED", with its intervals.
  std::map<std::string, std::vector<Interval>> led_intervals() const;
  // Is any LED line active at the end of the timeline?
  std::vector<std::string> leds_left_on() const;

 private:
  std::vector<TimelineEntry> entries_;
};

struct DomeOptions {
  std::filesystem::path rig;               // default: hw/rigs/sim-dome.yaml
  std::vector<std::string> sim_args;       // extra lightstage-sim flags (strobe, faults)
  std::vector<std::string> firmware_args;  // extra lightstage-domed flags
  bool camera = false;                     // serve the virtual camera too (sim_args set the scene)
};

// The host's SimulatedDome in the test's scratch folder, with the timeline
// recorded and both programs' logs printed when the test failed.
class SimulatedDome : public lightstage::SimulatedDome {
 public:
  explicit SimulatedDome(DomeOptions options = {});
  ~SimulatedDome();

  std::unique_ptr<ControllerClient> connect(ControllerClientOptions options = {}) const;
  // Stops the firmware (SIGTERM) and the sim, expects clean exits, then loads the timeline.
  Timeline stop_and_read_timeline();
  Timeline read_timeline() const { return Timeline::load(timeline_file()); }
};

// Writes a copy of `rig` with every LED's limits replaced, for safety tests.
std::filesystem::path rig_with_limits(const std::filesystem::path& rig, double max_on_us, double max_duty,
                                      double duty_window_us, const std::filesystem::path& out);

}  // namespace lightstage::testing
