#include "commands.hpp"

namespace lightstage::cli {

const std::vector<Command>& commands() {
  static const std::vector<Command> table = {
      {"demo", add_demo},
      {"simulate", add_simulate},
      {"solve", add_solve},
      {"bench", add_bench},
      {"reflectance", add_reflectance},
      {"relight", add_relight},
      {"eval", add_eval},
      {"rig", add_rig},
      {"devices", add_devices},
      {"ctl", add_ctl},
      {"capture", add_capture},
      {"camera", add_camera},
      {"calibrate", add_calibrate},
      {"report", add_report},
      {"integrate", add_integrate},
  };
  return table;
}

}  // namespace lightstage::cli
