// lightstage-domed: the dome controller daemon. This build validates a rig and
// reports its safety limits (--check); the sequencer and protocol server stand
// on the same library.
#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/common/version.hpp"
#include "lightstage/hw/backends.hpp"

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <iostream>

int main(int argc, char** argv) {
  CLI::App app{"lightstage-domed: sequences a dome's LEDs and camera trigger, within hard safety limits."};
  std::string rig_path = lightstage::default_rig_path().string();
  bool check = false;
  bool version = false;
  app.add_option("--rig", rig_path, "rig description (YAML)")->capture_default_str();
  app.add_flag("--check", check, "validate the rig, print its wiring and limits, and exit");
  app.add_flag("--version", version, "print the version and the hardware backends built in");
  CLI11_PARSE(app, argc, argv);
  try {
    if (version) {
      fmt::print("lightstage-domed {}\n", lightstage::kVersion);
      for (const auto& backend : lightstage::hw::hardware_backends()) {
        fmt::print("  {:10} {:40} {}\n", backend.scheme + ":", backend.what,
                   backend.built ? "built" : "not built");
      }
      return 0;
    }
    const lightstage::Rig rig = lightstage::load_rig(rig_path);
    double shortest_on = 1e300;
    double lowest_duty = 1;
    for (const auto& led : rig.leds) {
      shortest_on = std::min(shortest_on, led.limits.max_on_us);
      lowest_duty = std::min(lowest_duty, led.limits.max_duty);
    }
    fmt::print("{}: rig '{}' is valid: {} LEDs, {} shift-register chain(s), trigger {}{}\n", rig_path,
               rig.name, rig.leds.size(), rig.chains.size(), rig.trigger.line.describe(),
               rig.strobe ? ", strobe " + rig.strobe->line.describe() : std::string());
    fmt::print("limits: max on-time {:.0f} us, max duty {:.2f} (tightest over all LEDs)\n", shortest_on,
               lowest_duty);
    if (!check) {
      lightstage::logger("firmware")
          ->error("no GPIO backend given: the sequencer needs --gpio (see issue 3)");
      return 2;
    }
    return 0;
  } catch (const lightstage::Error& e) {
    std::cerr << "lightstage-domed: " << e.what() << "\n";
    return 1;
  }
}
