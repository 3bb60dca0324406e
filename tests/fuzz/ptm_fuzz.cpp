// PTM files come from other tools (RTIBuilder, RTIViewer): parsing any bytes
// must give an RTI image or an InputError, never a crash; what parses writes back.
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/rti_files.hpp"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto image = lightstage::io::parse_ptm(text, "fuzz.ptm");
    (void)lightstage::io::format_ptm(image, lightstage::io::PtmFormat::rgb);
  } catch (const lightstage::InputError&) {
  }
  return 0;
}
