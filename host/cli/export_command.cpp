// `lightstage export`: a stack as an RTI file other tools open (PTM, HSH).
#include "commands.hpp"
#include "lightstage/pipeline/rti_exchange.hpp"

#include <fmt/format.h>

namespace lightstage::cli {

void add_export(CLI::App& app) {
  struct Args {
    pipeline::ExportSettings settings;
    std::string input, out;
  };
  auto args = std::make_shared<Args>();
  pipeline::ExportSettings* s = &args->settings;
  CLI::App* sub = app.add_subcommand(
      "export",
      "Fit a stack per pixel and write it as an RTI file (layouts and sources: docs/rti-formats.md).\n"
      "ptm: PTM 1.2 biquadratic in the light's (lu, lv), PTM_FORMAT_LRGB (default) or PTM_FORMAT_RGB "
      "(--colour rgb), as RTIViewer reads it. hsh: hemispherical harmonics .rti, order 3 (9 terms, default) "
      "or 2 (4 terms). Values are the stack's linear values (radiometry without its grey conversion).\n"
      "Example: lightstage export --input stack --format ptm --out object.ptm\n"
      "         lightstage export --input stack --format hsh --order 3 --out object.rti");
  sub->add_option("--input", args->input, "stack folder")->required();
  sub->add_option("--out", args->out, "file to write (must not exist)")->required();
  sub->add_option("--format", s->format, "ptm | hsh")->capture_default_str();
  sub->add_option("--colour", s->colour, "PTM colour layout: lrgb | rgb")->capture_default_str();
  sub->add_option("--order", s->hsh_order, "HSH order: 2 | 3")->capture_default_str();
  sub->callback([args] {
    args->settings.input = args->input;
    args->settings.out = args->out;
    const nlohmann::json r = pipeline::export_rti(args->settings);
    fmt::print("wrote {} ({} {}x{}, {} terms from {} lights)\n", r["out"].get<std::string>(),
               r["model"].get<std::string>(), r["width"].get<int>(), r["height"].get<int>(),
               r["terms"].get<int>(), r["lights"].get<std::size_t>());
  });
}

}  // namespace lightstage::cli
