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
#include <memory>
#include <sstream>

namespace {

// Lists subcommands by the first line of their description: `lightstage
// --help` stays one screen, `lightstage COMMAND --help` has the whole text.
class SummaryFormatter : public CLI::Formatter {
 public:
  std::string make_subcommand(const CLI::App* sub) const override {
    const std::string& description = sub->get_description();
    std::stringstream out;
    CLI::detail::format_help(out, sub->get_display_name(true), description.substr(0, description.find('\n')),
                             get_column_width());
    return out.str();
  }
};

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
      "LEDs, and turn them into surface normals, albedo, depth, meshes, relit images and error reports.\n"
      "\n"
      "The usual path: `simulate` (or `capture` on a rig, after `calibrate` and `camera`) writes a stack "
      "folder; `solve` turns it into normal.png, albedo and summary.json; `integrate` makes depth and a "
      "mesh; "
      "`eval`, `report` and `relight` look at the result. `demo` runs the first steps end to end. Every "
      "file format is described under docs/ (stack-format.md, solvers.md, surfaces.md, ...).\n"
      "\n"
      "Output: results on stdout, logs and errors on stderr. The long commands (demo, simulate, capture, "
      "solve, integrate, bench) draw a progress line with the time left when stderr is a terminal; --quiet "
      "turns it off (they then print nothing but errors) and --json prints exactly one JSON object on "
      "stdout. Bad input exits non-zero with one line naming the flag or file. "
      "`lightstage COMMAND --help` describes a command.\n"
      "\n"
      "Example, end to end on the simulated dome:\n"
      "  lightstage demo --out out/demo",
      "lightstage"};
  app.formatter(std::make_shared<SummaryFormatter>());
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
