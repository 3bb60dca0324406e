// `lightstage relight`: render a solved object under new lights.
#include "commands.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/host/reflectance/relight.hpp"
#include "lightstage/pipeline/relight_folder.hpp"

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
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "relight",
      "Render a solved object under new distant lights from its normals and per-pixel BRDFs.\n"
      "Reads a `solve` output folder (a bi-polynomial or auto solve carries per-pixel BRDF coefficients; "
      "other methods relight with their Lambertian albedo) and writes one 16-bit PNG per light "
      "(relit_000.png, ...; value = min(v / scale, 1) * 65535) plus relight.json.\n"
      "Example: lightstage relight --input out/result --light 0.5,0.3,0.8 --light -0.5,0,0.8 --out "
      "out/relit\n"
      "         lightstage relight --input out/result --turntable 36 --elevation 40 --out out/turntable");
  sub->add_option("--input", args->input, "solve output folder")->required();
  sub->add_option("--out", args->out, "output folder")->required();
  sub->add_option("--light", args->lights, "light direction x,y,z (object -> light); repeatable");
  sub->add_option("--turntable", args->turntable, "N frames with the light circling the object");
  sub->add_option("--elevation", args->elevation, "turntable light elevation, degrees")
      ->capture_default_str();
  sub->add_option("--scale", args->scale, "value mapped to white (0 = the 99.5th percentile of all frames)");
  sub->callback([args] {
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
    const nlohmann::json summary = pipeline::relight_folder(settings);
    fmt::print("relit {} frames ({} model) -> {}\n", summary["frames"].size(),
               summary["order"].get<int>() > 0 ? "bi-polynomial" : "Lambertian", args->out);
  });
}

}  // namespace lightstage::cli
