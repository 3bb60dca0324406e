// `lightstage demo`: the pipeline end to end on the simulated dome, as three processes.
#include "commands.hpp"
#include "lightstage/pipeline/dome_demo.hpp"
#include "options.hpp"

#include <fmt/format.h>

namespace lightstage::cli {

void add_demo(CLI::App& app) {
  struct Args {
    std::string rig = default_rig_path().string();
    std::string programs;
    std::string exposure = "auto";
    OutputFlags output;
    pipeline::DomeDemoOptions demo;
  };
  auto args = std::make_shared<Args>();
  args->demo.out = "out/demo";
  CLI::App* sub = app.add_subcommand(
      "demo",
      "Run the whole pipeline on the simulated dome, as on a rig.\n"
      "\n"
      "Starts lightstage-sim (a virtual gpiochip and camera) and lightstage-domed (the dome firmware on "
      "it) as separate processes, then, through the controller protocol and the sim: camera: captures a "
      "chrome sphere at two positions, calibrates light directions and LED positions from them, captures "
      "the object (automatic exposure, dark frames), solves it with the calibrated near lights, "
      "integrates a surface and writes the report. The programs are stopped after each capture and on "
      "every error, and die with the demo if it is killed.\n"
      "Output, in --out: calibration/ (the two chrome stacks and calibration.json), capture/ (the "
      "object's stack, with the simulator's ground truth), result/ (normals, albedo, report.html), "
      "surface/ (depth.pfm, mesh.ply), dome/ (the programs' logs) and demo.json (the summary: "
      "calibration and normal errors against the simulator's truth, timings).\n"
      "\n"
      "Example: lightstage demo --out out/demo --scene bunny --method robust");
  sub->add_option("--rig", args->rig, "rig description (YAML)")->capture_default_str();
  sub->add_option("--out", args->demo.out, "output folder (what an earlier demo wrote there is replaced)")
      ->capture_default_str();
  sub->add_option("--scene", args->demo.scene,
                  "the object: a scene preset or scene YAML (docs/scene-format.md)")
      ->capture_default_str();
  sub->add_option("--material", args->demo.material, "material preset overriding the scene's");
  sub->add_option("--width", args->demo.width, "image width (default: the rig camera's)");
  sub->add_option("--height", args->demo.height, "image height (default: the rig camera's)");
  sub->add_option("--noise", args->demo.noise, "sensor noise: none or physical")->capture_default_str();
  sub->add_option("--seed", args->demo.seed, "sensor noise seed")->capture_default_str();
  sub->add_option("--exposure-us", args->exposure, "object exposure in us, or auto (per LED, from a preview)")
      ->capture_default_str();
  sub->add_option("--dark-frames", args->demo.capture.dark_frames, "dark frames averaged per exposure")
      ->capture_default_str();
  sub->add_option(
         "--camera", args->demo.camera,
         "sim: the simulator's machine-vision camera; dslr: a simulated DSLR fired through its remote "
         "port, its RAW (DNG) files taken from a folder (default rig: sim-dome-dslr.yaml)")
      ->check(CLI::IsMember({"sim", "dslr"}))
      ->capture_default_str();
  sub->add_option("--dslr-drop-rate", args->demo.dslr_drop_rate,
                  "--camera dslr: the share of shots whose file never arrives (each is retaken)")
      ->capture_default_str();
  sub->add_option("--programs", args->programs,
                  "folder holding lightstage-sim and lightstage-domed (default: this program's folder)");
  add_solve_flags(*sub, args->demo.solve);
  add_output_flags(*sub, args->output, "demo.json: the stages' results, errors against the truth, timings");
  sub->callback([sub, args] {
    apply_output_flags(*sub, args->output);
    pipeline::DomeDemoOptions demo = args->demo;
    demo.rig = args->rig;
    if (demo.camera == "dslr" && sub->count("--rig") == 0) demo.rig = rig_directory() / "sim-dome-dslr.yaml";
    demo.programs = args->programs;
    demo.capture.exposure_us = parse_exposure_us(args->exposure);
    demo.mode = args->output.mode();
    demo.solve.resolve();  // a bad flag fails before any program starts
    const nlohmann::json summary = pipeline::run_dome_demo(demo);
    if (args->output.json) fmt::print("{}\n", summary.dump());
  });
}

}  // namespace lightstage::cli
