#include "commands.hpp"

#include "lightstage/common/error.hpp"

namespace lightstage::cli {

const std::vector<Command>& commands() {
  static const std::vector<Command> table = {
      {"demo", add_demo},       {"simulate", add_simulate},
      {"solve", add_solve},     {"batch", add_batch},
      {"bench", add_bench},     {"reflectance", add_reflectance},
      {"relight", add_relight}, {"eval", add_eval},
      {"rig", add_rig},         {"devices", add_devices},
      {"ctl", add_ctl},         {"capture", add_capture},
      {"camera", add_camera},   {"calibrate", add_calibrate},
      {"report", add_report},   {"integrate", add_integrate},
      {"export", add_export},   {"import", add_import},
      {"serve", add_serve},
  };
  return table;
}

std::optional<double> parse_exposure_us(const std::string& text) {
  if (text == "auto") return std::nullopt;
  try {
    std::size_t used = 0;
    const double value = std::stod(text, &used);
    if (used == text.size() && value > 0) return value;
  } catch (const std::exception&) {
  }
  fail("--exposure-us: '{}' is not a positive number or auto", text);
}

}  // namespace lightstage::cli
