// RTI .lp files come from other tools: parsing any bytes must give light
// entries or an InputError, never a crash.
#include "lightstage/common/error.hpp"
#include "lightstage/host/calibration/lp_file.hpp"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto entries = lightstage::calibration::parse_lp(text, "fuzz.lp");
    (void)lightstage::calibration::format_lp(entries);
  } catch (const lightstage::InputError&) {
  }
  return 0;
}
