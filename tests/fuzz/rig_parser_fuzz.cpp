// Rig files come from users: any bytes must give a rig or an InputError.
#include "lightstage/common/error.hpp"
#include "lightstage/common/rig.hpp"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const lightstage::Rig rig = lightstage::parse_rig(text, "fuzz.yaml");
    for (const auto& led : rig.leds) (void)rig.light_direction(led);
  } catch (const lightstage::InputError&) {
  }
  return 0;
}
