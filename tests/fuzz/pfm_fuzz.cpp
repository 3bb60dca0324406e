// PFM files come from other tools (depth priors, float maps): any bytes must
// give an image or an InputError.
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/pfm.hpp"

#include "fuzz_scratch.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path path = lightstage::fuzzing::scratch_dir() / "input.pfm";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    const cv::Mat image = lightstage::io::read_pfm(path);
    (void)cv::sum(image);
  } catch (const lightstage::InputError&) {
  }
  return 0;
}
