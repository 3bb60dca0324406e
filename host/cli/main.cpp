// lightstage: the host program. Subcommands come from the table in
// commands.cpp; errors from bad input are caught here, once, and printed on
// one line with a non-zero exit.
#include "commands.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/version.hpp"
#include "lightstage/hw/backends.hpp"

#include <fmt/format.h>

#include <exception>
#include <iostream>

namespace {

void print_version() {
  fmt::print("lightstage {}\n", lightstage::kVersion);
  for (const auto& backend : lightstage::hw::hardware_backends()) {
    fmt::print("  {:11}{:40}{}\n", backend.scheme + ":", backend.what,
               backend.built ? "compiled in" : "not compiled in");
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "lightstage: photometric stereo on a light stage. Simulate or capture image stacks under a dome of "
      "LEDs, and turn them into surface normals, albedo and error reports.\n\n"
      "Example, end to end on the simulated dome:\n"
      "  lightstage demo --out out/demo"};
  app.require_subcommand(0, 1);
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")
      ->capture_default_str()
      ->trigger_on_parse()
      ->each([](const std::string& level) { lightstage::set_log_level(level); });
  app.add_flag_callback(
      "--version",
      [] {
        print_version();
        throw CLI::Success();
      },
      "print the version and the hardware backends compiled in");
  for (const auto& command : lightstage::cli::commands()) command.add(app);

  try {
    app.parse(argc, argv);
    if (app.get_subcommands().empty()) {
      std::cout << app.help();
      return 2;
    }
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const lightstage::Error& e) {
    std::cerr << "lightstage: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "lightstage: internal error: " << e.what() << "\n";
    return 3;
  }
  return 0;
}
