#pragma once
// `lightstage serve --simulated`: the simulated dome's programs
// (lightstage-sim with its camera, lightstage-domed on it), started by the
// station as `demo` starts them. What lies under the dome is the operator's
// choice on a real rig; here the page chooses it: the object, or the chrome
// sphere at one of its calibration positions. Placing restarts the programs
// with that scene (the station reconnects).

#include "lightstage/host/demo/simulated_dome.hpp"
#include "lightstage/pipeline/socket_folder.hpp"

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
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

  // "object" or "chrome-K"; throws Refused(400) naming the choices for anything else.
  void place(const std::string& what);
  const std::string& placed() const { return placed_; }
  std::vector<std::string> choices() const;
  std::string controller_uri() const { return dome_->controller_uri(); }
  std::string camera_uri() const { return dome_->camera_uri(); }
  nlohmann::json to_json() const;

 private:
  void start(const std::string& what);

  SimulatedBenchOptions options_;
  pipeline::SocketFolder sockets_;
  std::string placed_;
  int starts_ = 0;
  std::unique_ptr<SimulatedDome> dome_;
};

}  // namespace lightstage::station
