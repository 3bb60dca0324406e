// `lightstage import rti`: a dome operator's folder of photographs plus .lp as a stack.
#include "commands.hpp"
#include "lightstage/pipeline/rti_exchange.hpp"

#include <fmt/format.h>

namespace lightstage::cli {

void add_import(CLI::App& app) {
  CLI::App* import =
      app.add_subcommand("import", "Make a stack folder from files of other tools.\nSubcommand: rti.");
  import->require_subcommand(1);
  struct Args {
    std::string input, lp, response, out, raw_demosaic = "half";
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = import->add_subcommand(
      "rti",
      "A folder of JPEG / PNG / 16-bit TIFF / camera RAW (DNG, CR2, CR3, NEF, ARW, ...) photographs and an "
      ".lp "
      "file (one line per photo: name and light direction) becomes a stack folder (docs/stack-format.md). "
      "8-bit "
      "images are linearised with the sRGB curve, or with --response (a `camera response` JSON); 16-bit "
      "TIFF/PNG "
      "are taken as linear; RAW files are decoded linear (black and white level only, no white balance or "
      "curve). Each frame's EXIF (exposure, ISO, aperture, time) goes into the manifest.\n"
      "Example: lightstage import rti captures/coin --out stacks/coin\n"
      "         lightstage import rti captures/coin --lp captures/coin/assembly.lp --response resp.json "
      "--out "
      "stacks/coin");
  sub->add_option("DIR", args->input, "folder of photographs")->required();
  sub->add_option("--lp", args->lp, "the .lp file (default: the one .lp in DIR)");
  sub->add_option("--response", args->response, "inverse camera response JSON for 8-bit images");
  sub->add_option("--out", args->out, "stack folder to create (absent or empty)")->required();
  sub->add_option(
         "--raw-demosaic", args->raw_demosaic,
         "RAW files: half (each 2x2 Bayer block one pixel, exactly linear, half size) or full (LibRaw's "
         "demosaic at full size)")
      ->check(CLI::IsMember({"half", "full"}))
      ->capture_default_str();
  sub->callback([args] {
    const nlohmann::json r =
        pipeline::import_rti({args->input, args->lp, args->response, args->out,
                              io::parse_raw_demosaic(args->raw_demosaic, "--raw-demosaic")});
    fmt::print("imported {} images ({} linearised) -> {}\n", r["images"].size(),
               r["linearised"].get<std::string>(), args->out);
  });
}

}  // namespace lightstage::cli
