#include "lightstage/station/simulated_bench.hpp"

#include "lightstage/common/rig.hpp"
#include "lightstage/pipeline/dome_demo.hpp"
#include "lightstage/station/operator_access.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <fstream>

namespace lightstage::station {

namespace fs = std::filesystem;

SimulatedBench::SimulatedBench(SimulatedBenchOptions options) : options_(std::move(options)) {
  start("object");
}

SimulatedBench::~SimulatedBench() = default;

std::vector<std::string> SimulatedBench::choices() const {
  std::vector<std::string> names = {"object"};
  for (std::size_t k = 0; k < options_.sphere_x_mm.size(); ++k)
    names.push_back(fmt::format("chrome-{}", k + 1));
  return names;
}

void SimulatedBench::place(const std::string& what) {
  const auto names = choices();
  if (std::find(names.begin(), names.end(), what) == names.end())
    throw Refused(400, fmt::format("place: '{}' is none of {}", what, fmt::join(names, ", ")));
  if (what == placed_) return;
  start(what);
}

void SimulatedBench::start(const std::string& what) {
  dome_.reset();  // the programs stop (the dome dark) before others start on the same sockets
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
  dome_ = std::make_unique<SimulatedDome>(dome);
  placed_ = what;
}

nlohmann::json SimulatedBench::to_json() const {
  return {{"placed", placed_}, {"choices", choices()}, {"scene", options_.scene}};
}

}  // namespace lightstage::station
