// calibration.json files come from users and other machines: reading any
// bytes must give a calibration or an InputError, never a crash.
#include "lightstage/common/error.hpp"
#include "lightstage/host/calibration/light_calibration.hpp"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded()) return 0;
  try {
    const auto calibration = lightstage::calibration::calibration_from_json(j, "fuzz.json");
    (void)lightstage::calibration::directions_text(calibration);
    (void)lightstage::calibration::to_json(calibration).dump();
  } catch (const lightstage::InputError&) {
  }
  return 0;
}
