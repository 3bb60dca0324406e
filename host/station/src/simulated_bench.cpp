#include "lightstage/station/simulated_bench.hpp"

#include "lightstage/common/rig.hpp"
#include "lightstage/pipeline/dome_demo.hpp"
#include "lightstage/station/operator_access.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <fstream>
#include <utility>

namespace lightstage::station {

namespace fs = std::filesystem;

SimulatedBench::SimulatedBench(SimulatedBenchOptions options)
    : options_(std::move(options)), launcher_([this] { launcher_loop(); }) {
  try {
    on_launcher([this] { start("object"); });
  } catch (...) {
    {
      const std::lock_guard lock(launch_mutex_);
      launcher_quit_ = true;
    }
    launch_changed_.notify_all();
    launcher_.join();
    throw;
  }
}

SimulatedBench::~SimulatedBench() {
  {
    const std::lock_guard lock(mutex_);
    dome_.reset();  // the programs end here, not by the launcher's death signal
  }
  {
    const std::lock_guard lock(launch_mutex_);
    launcher_quit_ = true;
  }
  launch_changed_.notify_all();
  launcher_.join();
}

void SimulatedBench::launcher_loop() {
  std::unique_lock lock(launch_mutex_);
  for (;;) {
    launch_changed_.wait(lock, [this] { return launcher_quit_ || launch_task_; });
    if (launcher_quit_) return;
    const std::function<void()> task = std::move(launch_task_);
    launch_task_ = nullptr;
    lock.unlock();
    std::exception_ptr error;
    try {
      task();
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    launch_error_ = error;
    launch_done_ = true;
    launch_changed_.notify_all();
  }
}

void SimulatedBench::on_launcher(const std::function<void()>& task) {
  const std::lock_guard one_caller(launch_caller_mutex_);
  std::unique_lock lock(launch_mutex_);
  launch_task_ = task;
  launch_done_ = false;
  launch_changed_.notify_all();
  launch_changed_.wait(lock, [this] { return launch_done_; });
  if (launch_error_) std::rethrow_exception(std::exchange(launch_error_, nullptr));
}

std::vector<std::string> SimulatedBench::choices() const {
  std::vector<std::string> names = {"object"};
  for (std::size_t k = 0; k < options_.sphere_x_mm.size(); ++k)
    names.push_back(fmt::format("chrome-{}", k + 1));
  return names;
}

void SimulatedBench::check_choice(const std::string& what) const {
  const auto names = choices();
  if (std::find(names.begin(), names.end(), what) == names.end())
    throw Refused(400, fmt::format("place: '{}' is none of {}", what, fmt::join(names, ", ")));
}

void SimulatedBench::place(const std::string& what) {
  check_choice(what);
  if (what == placed()) return;
  on_launcher([&] { start(what); });
}

std::string SimulatedBench::placed() const {
  const std::lock_guard lock(mutex_);
  return placed_;
}

std::string SimulatedBench::controller_uri() const {
  const std::lock_guard lock(mutex_);
  if (!dome_) throw Error("the simulated dome's programs are not running (the last placement failed)");
  return dome_->controller_uri();
}

std::string SimulatedBench::camera_uri() const {
  const std::lock_guard lock(mutex_);
  if (!dome_) throw Error("the simulated dome's programs are not running (the last placement failed)");
  return dome_->camera_uri();
}

void SimulatedBench::start(const std::string& what) {
  {
    // The programs stop (the dome dark) before others start on the same sockets.
    const std::lock_guard lock(mutex_);
    dome_.reset();
    placed_.clear();
  }
  std::vector<std::string> args = {"--noise",  options_.noise, "--seed", std::to_string(options_.seed),
                                   "--lights", "near"};
  if (what == "object") {
    args.insert(args.end(), {"--scene", options_.scene});
    if (!options_.material.empty()) args.insert(args.end(), {"--material", options_.material});
  } else {
    const std::size_t k = std::stoul(what.substr(what.find('-') + 1)) - 1;
    const Rig rig = load_rig(options_.rig);
    const fs::path scene = options_.log_dir / (what + ".yaml");
    fs::create_directories(scene.parent_path());
    std::ofstream(scene) << pipeline::chrome_sphere_scene(options_.sphere_radius_mm, options_.sphere_x_mm[k],
                                                          rig.object_position_mm.z());
    args.insert(args.end(), {"--scene", scene.string()});
  }
  if (options_.width) args.insert(args.end(), {"--width", std::to_string(*options_.width)});
  if (options_.height) args.insert(args.end(), {"--height", std::to_string(*options_.height)});
  SimulatedDomeOptions dome;
  dome.rig = options_.rig;
  dome.log_dir = options_.log_dir / fmt::format("{}-{}", ++starts_, what);
  dome.socket_dir = sockets_.path();
  dome.program_dir = options_.programs;
  dome.sim_args = args;
  dome.camera = true;
  auto started = std::make_unique<SimulatedDome>(dome);
  const std::lock_guard lock(mutex_);
  dome_ = std::move(started);
  placed_ = what;
}

nlohmann::json SimulatedBench::to_json() const {
  return {{"placed", placed()}, {"choices", choices()}, {"scene", options_.scene}};
}

}  // namespace lightstage::station
