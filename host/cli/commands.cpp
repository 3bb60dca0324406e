#include "commands.hpp"

namespace lightstage::cli {

const std::vector<Command>& commands() {
  static const std::vector<Command> table = {
      {"demo", add_demo}, {"simulate", add_simulate}, {"solve", add_solve},
      {"eval", add_eval}, {"rig", add_rig},           {"devices", add_devices}, {"ctl", add_ctl},
  };
  return table;
}

}  // namespace lightstage::cli
