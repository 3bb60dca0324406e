// `lightstage export`: a stack (or a solve of one) as RTI files other tools open (PTM, HSH, relight).
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
      "Fit a stack per pixel and write it as RTI files (layouts and sources: docs/rti-formats.md).\n"
      "ptm: PTM 1.2 biquadratic in the light's (lu, lv), PTM_FORMAT_LRGB (default) or PTM_FORMAT_RGB "
      "(--colour rgb), as RTIViewer reads it. hsh: hemispherical harmonics .rti, order 3 (9 terms, default) "
      "or 2 (4 terms). relight: the web format of CNR-ISTI's relight / OpenLIME, a folder with info.json and "
      "plane_0.jpg, plane_1.jpg, ... (--model ptm or hsh, --colour rgb (default) or lrgb, --planes png for "
      "lossless planes). Values are the stack's linear values (radiometry without its grey conversion).\n"
      "--input is a stack folder or a `solve` output folder: the fit needs the photographs, so a solve "
      "folder is followed to the stack its summary.json records as input (its normals and BRDF are not "
      "exported) and the export is the same as of that stack.\n"
      "Example: lightstage export --input stack --format ptm --out object.ptm\n"
      "         lightstage export --input stack --format hsh --order 3 --out object.rti\n"
      "         lightstage export --input out/result --format relight --out object-web");
  sub->add_option("--input", args->input, "stack folder, or a solve folder of one")->required();
  sub->add_option("--out", args->out, "file (ptm, hsh) or new folder (relight) to write; must not exist")
      ->required();
  sub->add_option("--format", s->format, "ptm | hsh | relight")->capture_default_str();
  sub->add_option("--colour", s->colour,
                  "ptm, relight colour layout: lrgb | rgb (default: lrgb for ptm, rgb "
                  "for relight)");
  sub->add_option("--order", s->hsh_order, "HSH order: 2 | 3")->capture_default_str();
  sub->add_option("--model", s->model, "relight: the basis, ptm | hsh")->capture_default_str();
  sub->add_option("--planes", s->planes, "relight: plane images, jpg | png")->capture_default_str();
  sub->add_option("--quality", s->quality, "relight: JPEG quality of the planes")->capture_default_str();
  sub->callback([args] {
    args->settings.input = args->input;
    args->settings.out = args->out;
    const nlohmann::json r = pipeline::export_rti(args->settings);
    fmt::print("wrote {} ({} {} {}x{}, {} terms from {} lights of {}, {} files, {} bytes)\n",
               r["out"].get<std::string>(), r["format"].get<std::string>(), r["model"].get<std::string>(),
               r["width"].get<int>(), r["height"].get<int>(), r["terms"].get<int>(),
               r["lights"].get<std::size_t>(), r["stack"].get<std::string>(), r["files"].size(),
               r["bytes"].get<std::uintmax_t>());
    if (r.contains("note")) fmt::print("note: {}\n", r["note"].get<std::string>());
  });
}

}  // namespace lightstage::cli
