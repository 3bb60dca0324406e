#pragma once
// The simulated dome as the separate programs it is on a bench: lightstage-sim
// (the virtual gpiochip and, optionally, the virtual camera) and
// lightstage-domed (the real firmware on its sim: GPIO backend). The host then
// talks to them exactly as to a rig: a controller URI and a camera URI.
// Both programs stop when this object goes (SIGTERM, then SIGKILL), and with
// the parent process if it dies (see ChildProcess).

#include "lightstage/common/child_process.hpp"

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace lightstage {

struct SimulatedDomeOptions {
  std::filesystem::path rig;               // rig YAML, for both programs
  std::filesystem::path log_dir;           // sim.log, domed-N.log and (optional) timeline go here
  std::filesystem::path socket_dir;        // unix sockets (keep the path short: 108 bytes at most)
  std::filesystem::path program_dir;       // where lightstage-sim and lightstage-domed are; empty = ours
  std::vector<std::string> sim_args;       // extra lightstage-sim flags (scene, faults, strobe)
  std::vector<std::string> firmware_args;  // extra lightstage-domed flags
  bool camera = false;                     // serve the virtual camera too
  bool timeline = false;                   // record the GPIO timeline into log_dir/timeline.jsonl
  std::chrono::milliseconds start_timeout{20000};
};

class SimulatedDome {
 public:
  // Starts both programs and waits until each listens; throws Error with their logs otherwise.
  explicit SimulatedDome(SimulatedDomeOptions options);
  ~SimulatedDome();
  SimulatedDome(const SimulatedDome&) = delete;
  SimulatedDome& operator=(const SimulatedDome&) = delete;

  std::string controller_uri() const { return "unix:" + controller_socket_.string(); }
  std::string camera_uri() const { return "sim:" + camera_socket_.string(); }
  std::filesystem::path timeline_file() const { return options_.log_dir / "timeline.jsonl"; }
  const std::filesystem::path& rig() const { return options_.rig; }
  // Starts lightstage-domed again (after it was killed), on the same sockets.
  void restart_firmware();
  ChildProcess& sim() { return *sim_; }
  ChildProcess& firmware() { return *firmware_; }
  // Stops the firmware and then the sim (SIGTERM; SIGKILL after `grace`);
  // returns their exit codes (0 = clean, the dome was left dark).
  struct ExitCodes {
    int firmware = 0, sim = 0;
  };
  ExitCodes stop(std::chrono::milliseconds grace = std::chrono::seconds(10));
  // Both programs' logs, labelled, for error messages.
  std::string logs() const;

 private:
  void start_firmware();
  std::filesystem::path program(const std::string& name) const;

  SimulatedDomeOptions options_;
  std::filesystem::path sim_socket_, controller_socket_, camera_socket_;
  int firmware_starts_ = 0;
  std::unique_ptr<ChildProcess> sim_, firmware_;
};

}  // namespace lightstage
