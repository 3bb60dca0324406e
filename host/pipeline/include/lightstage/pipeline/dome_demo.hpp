#pragma once
// `lightstage demo`: the real pipeline on the simulated dome. lightstage-sim
// (virtual gpiochip and camera) and lightstage-domed (the firmware) run as
// their own processes; this process captures through the protocol and the
// sim: camera (or the simulated DSLR's files) exactly as on a rig — a chrome sphere at two positions for the
// light calibration, then the object — calibrates, solves with the
// calibrated (near) lights, integrates a surface and writes the report.

#include "lightstage/host/capture/capture_session.hpp"
#include "lightstage/host/progress.hpp"
#include "lightstage/pipeline/solve_settings.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::pipeline {

// lightstage-sim's scene of a chrome sphere (radius, centre in the dome
// frame, mm) on a dark stand: the light calibration's target.
std::string chrome_sphere_scene(double radius_mm, double x_mm, double z_mm);

// Lambertian least squares without the observations at or below 0.02: a
// capture has shadows.
SolveSettings default_demo_solve();

struct DomeDemoOptions {
  std::filesystem::path rig;
  std::filesystem::path out;
  std::filesystem::path programs;  // folder of lightstage-sim and lightstage-domed; empty = beside us
  // The object: what lightstage-sim's camera renders (the ground truth comes from the same world).
  std::string scene = "bunny";
  std::string material;  // empty = the scene's
  std::optional<int> width, height;
  std::string noise = "physical";  // none | physical
  std::uint64_t seed = 1;
  // Two chrome-sphere positions (dome frame, mm) and radius for the calibration: a
  // large sphere, far apart, as docs/calibration.md recommends for LED positions.
  double sphere_radius_mm = 25;
  std::vector<double> sphere_x_mm = {-25, 25};
  // sim: lightstage-sim's virtual camera (sim:); dslr: its simulated DSLR on
  // the remote port, writing DNGs that the host takes from the folder
  // (folder:) -- the rig must describe the DSLR's trigger (hw/rigs/sim-dome-dslr.yaml).
  std::string camera = "sim";
  double dslr_drop_rate = 0.02;  // the simulated DSLR loses this share of its shots, as real tethering does
  std::vector<std::string> dslr_args;          // more lightstage-sim --dslr-* flags
  CaptureOptions capture;                      // exposure, darks, loop; `out` and `mode` are set per stage
  SolveSettings solve = default_demo_solve();  // any method of the registry (solve_methods.hpp)
  OutputMode mode = OutputMode::kHuman;
};

// Runs every stage; the children are stopped on every exit path (also when a
// stage throws). Returns the summary also written to OUT/demo.json.
nlohmann::json run_dome_demo(const DomeDemoOptions& options);

}  // namespace lightstage::pipeline
