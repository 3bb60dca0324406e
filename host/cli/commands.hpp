#pragma once
// The `lightstage` subcommands, as a table: each entry adds one CLI11
// subcommand (its options bound to a library Options struct) whose callback
// is a thin call into the host library. main.cpp only walks the table.

#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

namespace lightstage::cli {

struct Command {
  const char* name;
  void (*add)(CLI::App& app);
};

const std::vector<Command>& commands();

// `--exposure-us` of capture and demo: microseconds, or "auto" (nullopt).
std::optional<double> parse_exposure_us(const std::string& text);

void add_demo(CLI::App& app);
void add_simulate(CLI::App& app);
void add_solve(CLI::App& app);
void add_batch(CLI::App& app);
void add_bench(CLI::App& app);
void add_reflectance(CLI::App& app);
void add_relight(CLI::App& app);
void add_eval(CLI::App& app);
void add_rig(CLI::App& app);
void add_devices(CLI::App& app);
void add_ctl(CLI::App& app);
void add_capture(CLI::App& app);
void add_camera(CLI::App& app);
void add_calibrate(CLI::App& app);
void add_report(CLI::App& app);
void add_integrate(CLI::App& app);
void add_export(CLI::App& app);
void add_import(CLI::App& app);
void add_serve(CLI::App& app);

}  // namespace lightstage::cli
