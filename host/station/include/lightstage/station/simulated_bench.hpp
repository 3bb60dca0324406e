#pragma once
// `lightstage serve --simulated`: the simulated dome's programs
// (lightstage-sim with its camera, lightstage-domed on it), started by the
// station as `demo` starts them. What lies under the dome is the operator's
// choice on a real rig; here the page chooses it: the object, or the chrome
// sphere at one of its calibration positions. Placing restarts the programs
// with that scene (the station reconnects).

#include "lightstage/host/demo/simulated_dome.hpp"
#include "lightstage/pipeline/socket_folder.hpp"

#include <condition_variable>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

namespace lightstage::station {

struct SimulatedBenchOptions {
  std::filesystem::path rig;
  std::filesystem::path programs;  // lightstage-sim and lightstage-domed; empty = beside this program
  std::filesystem::path log_dir;   // the programs' logs
  std::string scene = "bunny";     // the object
  std::string material;            // empty = the scene's
  std::optional<int> width, height;
  std::string noise = "physical";
  std::uint64_t seed = 1;
  double sphere_radius_mm = 25;                 // the chrome sphere
  std::vector<double> sphere_x_mm = {-25, 25};  // its positions, "chrome-1", "chrome-2", ...
};

class SimulatedBench {
 public:
  // Starts the programs with the object placed; throws Error with their logs when they do not start.
  explicit SimulatedBench(SimulatedBenchOptions options);
  ~SimulatedBench();
  SimulatedBench(const SimulatedBench&) = delete;
  SimulatedBench& operator=(const SimulatedBench&) = delete;

  // "object" or "chrome-K"; throws Refused(400) naming the choices for
  // anything else (the programs then run on as they were).
  void place(const std::string& what);
  void check_choice(const std::string& what) const;
  std::string placed() const;
  std::vector<std::string> choices() const;
  // Throw Error when the programs are not running (a placement failed to start them).
  std::string controller_uri() const;
  std::string camera_uri() const;
  nlohmann::json to_json() const;

 private:
  void start(const std::string& what);
  // Runs `task` on the thread that starts the programs: they get a death
  // signal when the thread that started them ends (ChildProcess), so that is
  // one thread living as long as the bench, not the HTTP worker that asked.
  void on_launcher(const std::function<void()>& task);
  void launcher_loop();

  SimulatedBenchOptions options_;
  pipeline::SocketFolder sockets_;
  int starts_ = 0;

  mutable std::mutex mutex_;  // placed_ and dome_, read by status polls
  std::string placed_;
  std::unique_ptr<SimulatedDome> dome_;

  std::mutex launch_caller_mutex_;  // one task at a time
  std::mutex launch_mutex_;
  std::condition_variable launch_changed_;
  std::function<void()> launch_task_;
  std::exception_ptr launch_error_;
  bool launch_done_ = false;
  bool launcher_quit_ = false;
  std::thread launcher_;
};

}  // namespace lightstage::station
