// relight's info.json comes from other tools (relight, relight-cli, web
// servers): parsing any text must give its fields or an InputError, never a
// crash, and what parses is consistent (planes and materials agree).
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/relight_web.hpp"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto info = lightstage::io::parse_relight_info(text, "fuzz/info.json");
    const int terms = lightstage::rti_term_count(info.basis);
    const bool rgb = info.colorspace == "rgb";
    if (info.scale.size() != static_cast<std::size_t>(info.nplanes) ||
        info.bias.size() != info.scale.size() || info.nplanes != (rgb ? 3 * terms : 3 + terms) ||
        info.width < 1 || info.height < 1)
      std::abort();
  } catch (const lightstage::InputError&) {
  }
  return 0;
}
