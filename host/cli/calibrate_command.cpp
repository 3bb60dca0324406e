// `lightstage calibrate lights`: light directions, LED positions and
// intensities from chrome-sphere (and matte) stacks.
#include "commands.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/host/calibration/calibrate_lights.hpp"
#include "lightstage/host/calibration/calibration_output.hpp"

#include <fmt/format.h>

#include <charconv>
#include <memory>

namespace lightstage::cli {
namespace {

using calibration::ImageCircle;

// "U,V,R" in pixels.
ImageCircle parse_circle(const std::string& text) {
  double values[3];
  const char* p = text.data();
  const char* end = p + text.size();
  for (int k = 0; k < 3; ++k) {
    const auto [next, ec] = std::from_chars(p, end, values[k]);
    if (ec != std::errc() || (k < 2 && (next == end || *next != ',')) || (k == 2 && next != end))
      fail("--sphere: expected U,V,R (centre and radius in pixels), got '{}'", text);
    p = next + 1;
  }
  ImageCircle circle;
  circle.centre_px = Vec2(values[0], values[1]);
  circle.radius_px = values[2];
  return circle;
}

}  // namespace

void add_calibrate(CLI::App& app) {
  struct Args {
    calibration::LightCalibrationOptions options;
    std::vector<std::string> inputs;
    std::vector<std::string> spheres;
    std::string rig;
    std::string intensity_target = "matte-sphere";
    std::string intensity_input;
    std::string compare;
    std::string out;
    double dome_radius = -1;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* calibrate = app.add_subcommand(
      "calibrate",
      "Calibrate the dome from captures of calibration targets (docs/calibration.md).\n"
      "Subcommand: lights (light directions, LED positions and intensities from chrome spheres, plus a "
      "matte target). `solve --calibration` and `report` use what it writes.\n"
      "Example: lightstage calibrate lights --input out/chrome --out out/cal");
  calibrate->require_subcommand(1);
  CLI::App* sub = calibrate->add_subcommand(
      "lights",
      "Light directions, LED positions and intensities from mirror spheres.\n"
      "\n"
      "Input: each --input is a stack folder (filenames.txt + images; no light files needed) of a chrome "
      "sphere under each light, and the rig (camera, object position, dome radius). The sphere outline "
      "comes from --sphere, else mask.png, else the median image; each image's highlight gives a mirror "
      "direction. Two or more sphere positions (several --input, or --spheres 2) triangulate LED "
      "positions; with one, the rig's dome radius places them. --intensity-input adds relative "
      "intensities from a matte sphere or a flat white target.\n"
      "Output, in --out: calibration.json, light_directions.txt, light_intensities.txt, lights.lp, "
      "lights_hemisphere.png and highlights.png (docs/calibration.md); prints a summary (or --json).\n"
      "\n"
      "Example: lightstage calibrate lights --input out/chrome --rig hw/rigs/sim-dome.yaml --out out/cal");
  sub->add_option("--input", args->inputs, "chrome-sphere stack folder (repeat for more sphere positions)")
      ->required();
  sub->add_option("--out", args->out, "output folder")->required();
  sub->add_option("--rig", args->rig,
                  "rig description: camera, object position, dome radius and nominal LED positions "
                  "('default' = the default rig)");
  sub->add_option("--spheres", args->options.spheres_per_stack, "spheres in each stack")
      ->capture_default_str();
  sub->add_option("--sphere", args->spheres,
                  "sphere outline U,V,R in pixels instead of detection (repeatable)");
  sub->add_option("--sphere-z-mm", args->options.sphere_z_mm,
                  "orthographic camera: height of the sphere centres, one for all or one per --input "
                  "(default: the rig's object position)");
  sub->add_option("--sphere-radius-mm", args->options.sphere_radius_mm,
                  "pinhole camera: the spheres' radius");
  sub->add_option("--dome-radius-mm", args->dome_radius,
                  "one sphere position: place LEDs on a dome of this radius (default: the rig's; 0 = distant "
                  "directions)");
  sub->add_option("--intensity-input", args->intensity_input,
                  "stack of a matte sphere or flat white target under the same lights");
  sub->add_option("--intensity-target", args->intensity_target, "matte-sphere or flat-target")
      ->check(CLI::IsMember({"matte-sphere", "flat-target"}))
      ->capture_default_str();
  sub->add_option("--min-peak", args->options.highlight.min_peak,
                  "a highlight must rise this far above the median image (fraction of full scale)")
      ->capture_default_str();
  sub->add_option("--compare", args->compare,
                  "reference light_directions.txt (or a folder holding one): report the angles to it");
  sub->add_flag("--allow-missing", args->options.allow_missing,
                "write a calibration even when some lights have no usable highlight");
  sub->add_option("--threads", args->options.threads, "threads (0 = all cores)")->capture_default_str();
  sub->add_flag("--json", args->json, "print the summary as JSON on stdout");
  sub->callback([args] {
    auto& o = args->options;
    for (const auto& input : args->inputs) o.inputs.emplace_back(input);
    for (const auto& text : args->spheres) o.given_circles.push_back(parse_circle(text));
    if (!args->rig.empty())
      o.rig = args->rig == "default" ? default_rig_path() : std::filesystem::path(args->rig);
    if (args->dome_radius >= 0) o.dome_radius_mm = args->dome_radius;
    if (!args->intensity_input.empty()) {
      o.intensity_input = args->intensity_input;
      o.intensity_target = calibration::parse_intensity_target(args->intensity_target);
    }
    const auto run = calibration::calibrate_lights(o);
    for (const auto& problem : run.calibration.problems) logger("host")->warn("{}", problem);
    nlohmann::json summary = calibration::write_calibration_outputs(args->out, run, o.inputs);
    std::optional<calibration::DirectionComparison> comparison;
    if (!args->compare.empty()) {
      std::filesystem::path reference = args->compare;
      if (std::filesystem::is_directory(reference)) reference /= "light_directions.txt";
      comparison = calibration::compare_directions(run.calibration, reference);
      summary["comparison"] = comparison->to_json();
      summary["comparison"]["reference"] = reference.string();
    }
    if (args->json) {
      fmt::print("{}\n", summary.dump());
      return;
    }
    fmt::print("calibrated {} of {} lights ({} directions, {} sphere(s)) in {:.2f} s into {}\n",
               summary["measured"].get<std::size_t>(), summary["lights"].get<std::size_t>(),
               run.calibration.direction_method, run.calibration.spheres.size(), run.seconds, args->out);
    if (run.calibration.nominal_fit) {
      const auto& fit = *run.calibration.nominal_fit;
      fmt::print(
          "LED positions vs the rig: rigid fit moves {:.2f} mm / {:.3f} deg; per-LED corrections RMS {:.2f} "
          "mm, "
          "max {:.2f} mm\n",
          fit.translation.norm(), fit.rotation_deg, fit.rms_mm, fit.max_mm);
    }
    if (comparison) {
      fmt::print("directions vs {}: mean {:.3f} deg, median {:.3f} deg, max {:.3f} deg over {} lights\n",
                 args->compare, comparison->mean_deg, comparison->median_deg, comparison->max_deg,
                 comparison->count);
    }
  });
}

}  // namespace lightstage::cli
