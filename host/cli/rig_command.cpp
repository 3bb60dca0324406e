// `lightstage rig`: validate a rig file and list its LEDs.
#include "commands.hpp"

#include "lightstage/common/rig.hpp"

#include <fmt/format.h>

#include <cmath>
#include <memory>

namespace lightstage::cli {

void add_rig(CLI::App& app) {
  struct Args {
    std::string rig = default_rig_path().string();
    bool list = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub =
      app.add_subcommand("rig",
                         "Validate a rig description and summarise it.\n"
                         "Reads a rig YAML file (docs/rig-format.md), checks every field, wiring "
                         "collision and limit, and prints a summary; --list adds one line per LED.\n"
                         "Example: lightstage rig --rig hw/rigs/matrix-64.yaml --list");
  sub->add_option("--rig", args->rig, "rig description (YAML)")->capture_default_str();
  sub->add_flag("--list", args->list, "list every LED: id, elevation, azimuth, wiring, limits");
  sub->callback([args] {
    const Rig rig = load_rig(args->rig);
    fmt::print("{}: '{}' — {} LEDs on a {:.0f} mm dome, {} chain(s), {} camera {}x{}\n", args->rig, rig.name,
               rig.leds.size(), rig.dome_radius_mm, rig.chains.size(),
               rig.camera.model == CameraModel::kPinhole ? "pinhole" : "orthographic", rig.camera.width,
               rig.camera.height);
    if (!args->list) return;
    fmt::print("{:>4} {:>9} {:>9} {:>10}  {:<16} {:>12} {:>8}\n", "id", "elev_deg", "azim_deg", "dist_mm",
               "wiring", "max_on_us", "max_duty");
    for (const Led& led : rig.leds) {
      const Vec3 dir = rig.light_direction(led);
      const std::string wiring = std::holds_alternative<DirectWiring>(led.wiring)
                                     ? std::get<DirectWiring>(led.wiring).line.describe()
                                     : fmt::format("{}[{}]", std::get<ChainWiring>(led.wiring).chain,
                                                   std::get<ChainWiring>(led.wiring).bit);
      fmt::print("{:>4} {:>9.2f} {:>9.2f} {:>10.1f}  {:<16} {:>12.0f} {:>8.2f}\n", led.id,
                 deg_from_rad(std::asin(dir.z())), deg_from_rad(std::atan2(dir.y(), dir.x())),
                 (led.position_mm - rig.object_position_mm).norm(), wiring, led.limits.max_on_us,
                 led.limits.max_duty);
    }
  });
}

}  // namespace lightstage::cli
