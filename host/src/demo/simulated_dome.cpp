#include "lightstage/host/demo/simulated_dome.hpp"

#include "lightstage/common/error.hpp"

#include <fmt/format.h>

#include <csignal>

namespace lightstage {

SimulatedDome::SimulatedDome(SimulatedDomeOptions options) : options_(std::move(options)) {
  if (options_.program_dir.empty()) options_.program_dir = own_program_dir();
  std::filesystem::create_directories(options_.log_dir);
  std::filesystem::create_directories(options_.socket_dir);
  sim_socket_ = options_.socket_dir / "sim.sock";
  controller_socket_ = options_.socket_dir / "domed.sock";
  camera_socket_ = options_.socket_dir / "camera.sock";
  if (controller_socket_.string().size() >= 100) {
    fail("socket folder '{}' is too long for unix sockets (at most ~100 bytes)",
         options_.socket_dir.string());
  }

  std::vector<std::string> args = {"--rig", options_.rig.string(), "--listen",
                                   "unix:" + sim_socket_.string()};
  if (options_.timeline) args.insert(args.end(), {"--timeline", timeline_file().string()});
  if (options_.camera) args.insert(args.end(), {"--camera", "unix:" + camera_socket_.string()});
  args.insert(args.end(), options_.sim_args.begin(), options_.sim_args.end());
  sim_ = std::make_unique<ChildProcess>(program("lightstage-sim"), args, options_.log_dir / "sim.log");
  if (!sim_->wait_for_output("listening on", options_.start_timeout)) {
    throw Error("lightstage-sim did not start:\n" + sim_->output());
  }
  start_firmware();
}

SimulatedDome::~SimulatedDome() {
  // Firmware first: it darkens the dome through the sim's lines before they go.
  if (firmware_) firmware_->terminate(std::chrono::seconds(10));
  if (sim_) sim_->terminate(std::chrono::seconds(10));
}

std::filesystem::path SimulatedDome::program(const std::string& name) const {
  const auto path = options_.program_dir / name;
  if (!std::filesystem::exists(path)) {
    fail("{} not found in {} (build it, or point --programs at the folder that holds it)", name,
         options_.program_dir.string());
  }
  return path;
}

void SimulatedDome::start_firmware() {
  std::vector<std::string> args = {"--rig",    options_.rig.string(), "--gpio", "sim:" + sim_socket_.string(),
                                   "--listen", controller_uri()};
  args.insert(args.end(), options_.firmware_args.begin(), options_.firmware_args.end());
  if (firmware_) firmware_->terminate(std::chrono::seconds(10));  // SIGTERM first: it darkens its lines
  firmware_.reset();
  firmware_ = std::make_unique<ChildProcess>(
      program("lightstage-domed"), args, options_.log_dir / fmt::format("domed-{}.log", ++firmware_starts_));
  if (!firmware_->wait_for_output("listening on", options_.start_timeout)) {
    throw Error("lightstage-domed did not start:\n" + logs());
  }
}

void SimulatedDome::restart_firmware() { start_firmware(); }

SimulatedDome::ExitCodes SimulatedDome::stop(std::chrono::milliseconds grace) {
  ExitCodes codes;
  if (firmware_) codes.firmware = firmware_->terminate(grace);
  if (sim_) codes.sim = sim_->terminate(grace);
  return codes;
}

std::string SimulatedDome::logs() const {
  return "--- lightstage-domed log ---\n" + (firmware_ ? firmware_->output() : "") +
         "--- lightstage-sim log ---\n" + (sim_ ? sim_->output() : "");
}

}  // namespace lightstage
