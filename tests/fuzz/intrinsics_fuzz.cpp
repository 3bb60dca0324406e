// Intrinsics files (K.txt) come from other tools: any text must give a valid
// matrix or an InputError.
#include "lightstage/common/error.hpp"
#include "lightstage/host/surface/camera.hpp"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto K = lightstage::surface::parse_intrinsics(
        std::string(reinterpret_cast<const char*>(data), size), "fuzz-K.txt");
    if (!(K(0, 0) > 0) || !(K(1, 1) > 0) || K(2, 2) != 1) __builtin_trap();
  } catch (const lightstage::InputError&) {
  }
  return 0;
}
