// `lightstage relight`: render a solved object under new lights.
#include "commands.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/host/reflectance/relight.hpp"
#include "lightstage/pipeline/relight_folder.hpp"
#include "lightstage/pipeline/rti_exchange.hpp"

#include <fmt/format.h>

#include <sstream>

namespace lightstage::cli {
namespace {

Vec3 parse_light(const std::string& text) {
  std::stringstream in(text);
  Vec3 v;
  char c1 = 0, c2 = 0;
  if (!(in >> v.x() >> c1 >> v.y() >> c2 >> v.z()) || c1 != ',' || c2 != ',' || !(in >> std::ws).eof())
    fail("--light: '{}' is not x,y,z", text);
  if (!v.allFinite() || v.norm() == 0) fail("--light: '{}' must be a finite, non-zero direction", text);
  return v;
}

}  // namespace

void add_relight(CLI::App& app) {
  struct Args {
    std::string input;
    std::string out;
    std::vector<std::string> lights;
    int turntable = 0;
    double elevation = 45;
    double scale = 0;
    bool holdout = false, json = false, grey = false;
    pipeline::HoldoutSettings holdout_settings;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "relight",
      "Render a solved object under new distant lights from its normals and per-pixel BRDFs.\n"
      "Reads a `solve` output folder (a bi-polynomial or auto solve carries per-pixel BRDF coefficients; "
      "other methods relight with their Lambertian albedo) and writes one 16-bit PNG per light "
      "(relit_000.png, ...; value = min(v / scale, 1) * 65535) plus relight.json. A solve of a colour stack "
      "relights in colour (the albedo's colour; a fitted specular lobe stays white); --grey for grey.\n"
      "With --holdout, --input is a stack folder instead and nothing is written: N lights evenly spaced in "
      "the stack's order are held out one at a time, every model is fitted on the other lights and relit at "
      "the held-out one, and the table gives relative RMSE = |relit - photo| / |photo| over the mask (grey "
      "values as solve uses them) averaged over the held-out lights: PTM, HSH order 2 and 3, l2 Lambertian "
      "(least-squares b, max(b.l, 0)) and the --methods (default biquadratic, auto), each solved with "
      "default settings, written as a solve folder and relit from it as above. The same as `bench "
      "holdout`.\n"
      "Example: lightstage relight --input out/result --light 0.5,0.3,0.8 --light -0.5,0,0.8 --out "
      "out/relit\n"
      "         lightstage relight --input out/result --turntable 36 --elevation 40 --out out/turntable\n"
      "         lightstage relight --holdout --input data/ballPNG --held-out 12 --methods biquadratic,auto");
  sub->add_option("--input", args->input, "solve output folder (with --holdout: a stack folder)")->required();
  sub->add_option("--out", args->out, "output folder (not with --holdout)");
  sub->add_option("--light", args->lights, "light direction x,y,z (object -> light); repeatable");
  sub->add_option("--turntable", args->turntable, "N frames with the light circling the object");
  sub->add_option("--elevation", args->elevation, "turntable light elevation, degrees")
      ->capture_default_str();
  sub->add_option("--scale", args->scale, "value mapped to white (0 = the 99.5th percentile of all frames)");
  sub->add_flag("--grey", args->grey, "grey images even when the solve is of a colour stack");
  sub->add_flag("--holdout", args->holdout, "leave-one-light-out relighting error of every model on a stack");
  sub->add_option("--held-out", args->holdout_settings.held_out, "--holdout: lights held out one at a time")
      ->capture_default_str();
  sub->add_option("--methods", args->holdout_settings.methods,
                  "--holdout: solve methods measured besides PTM, HSH and l2 (none: --methods none)")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--threads", args->holdout_settings.threads, "--holdout: solver threads (0 = all)")
      ->capture_default_str();
  sub->add_flag("--json", args->json, "--holdout: print the result as one JSON object");
  sub->callback([args] {
    if (args->holdout) {
      if (!args->out.empty() || !args->lights.empty() || args->turntable != 0 || args->grey)
        fail(
            "--holdout: measures on a stack and writes nothing; drop --out, --light, --turntable and --grey");
      args->holdout_settings.input = args->input;
      const nlohmann::json r = pipeline::rti_holdout(args->holdout_settings);
      if (args->json)
        fmt::print("{}\n", r.dump());
      else
        fmt::print("{}", pipeline::format_holdout_table(r));
      return;
    }
    if (args->out.empty()) fail("--out: required (the folder for the relit images)");
    std::vector<Vec3> lights;
    for (const auto& text : args->lights) lights.push_back(parse_light(text));
    if (args->turntable != 0) {
      const auto ring = turntable_lights(args->turntable, args->elevation);
      lights.insert(lights.end(), ring.begin(), ring.end());
    }
    pipeline::RelightSettings settings;
    settings.input = args->input;
    settings.out = args->out;
    settings.lights = lights;
    settings.scale = args->scale;
    settings.grey = args->grey;
    const nlohmann::json summary = pipeline::relight_folder(settings);
    fmt::print("relit {} {} frames ({} model) -> {}\n", summary["frames"].size(),
               summary["colour"].get<bool>() ? "colour" : "grey",
               summary["order"].get<int>() > 0 ? "bi-polynomial" : "Lambertian", args->out);
  });
}

}  // namespace lightstage::cli
