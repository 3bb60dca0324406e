// PLY meshes come from other tools (depth priors, scans): any bytes must give
// a mesh or an InputError.
#include "lightstage/common/error.hpp"
#include "lightstage/host/surface/mesh.hpp"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto mesh =
        lightstage::surface::parse_ply(std::string(reinterpret_cast<const char*>(data), size), "fuzz.ply");
    // Every face must refer to existing vertices.
    for (const auto& t : mesh.triangles)
      for (const auto i : t)
        if (i < 0 || static_cast<std::size_t>(i) >= mesh.vertices.size()) __builtin_trap();
  } catch (const lightstage::InputError&) {
  }
  return 0;
}
