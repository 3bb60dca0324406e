// EXR files come from other tools (depth priors, float images): any bytes must
// give a header and float pixels or an InputError. OpenEXR parses the header
// and decodes; io/exr.hpp bounds what a header may make it allocate. The
// first byte picks the channels asked for (the file's first, its first three,
// or R, G, B, which may be missing); the rest is the file, read from memory.
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/exr.hpp"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  try {
    const lightstage::io::ExrFile file(std::string(reinterpret_cast<const char*>(data + 1), size - 1),
                                       "fuzz.exr");
    const auto& header = file.header();
    std::vector<std::string> names;
    switch (data[0] % 3) {
      case 0:
        if (!header.channels.empty()) names.push_back(header.channels.front().name);
        break;
      case 1:
        for (std::size_t i = 0; i < header.channels.size() && i < 3; ++i)
          names.push_back(header.channels[i].name);
        break;
      default:
        names = {"R", "G", "B"};
    }
    if (names.empty()) return 0;
    const cv::Mat image = file.read(names);
    if (image.size() != header.size || image.channels() != static_cast<int>(names.size())) __builtin_trap();
  } catch (const lightstage::InputError&) {
  }
  return 0;
}
