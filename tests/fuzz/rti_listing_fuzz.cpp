// `import rti` lists images from an .lp file of another tool: any bytes must
// give image names inside the folder (no path parts, no "..") or an
// InputError, never a crash.
#include "lightstage/common/error.hpp"
#include "lightstage/host/calibration/lp_file.hpp"
#include "lightstage/host/io/rti_import.hpp"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    for (const auto& entry : lightstage::calibration::parse_lp(text, "fuzz.lp")) {
      const std::string name = lightstage::io::rti_image_name(entry.filename, "fuzz.lp");
      if (name.find_first_of("/\\") != std::string::npos || name == "..") std::abort();
    }
  } catch (const lightstage::InputError&) {
  }
  return 0;
}
