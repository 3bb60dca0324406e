// Scene files and `simulate --colour` specs come from users: any bytes must
// give a scene (or a colour) or an InputError.
#include "lightstage/common/error.hpp"
#include "lightstage/sim/scene_file.hpp"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const lightstage::sim::Scene scene = lightstage::sim::parse_scene(text, "fuzz.yaml");
    if (scene.material.colour) (void)scene.material.colour->eval(1.0, 2.0);
  } catch (const lightstage::InputError&) {
  }
  try {
    const lightstage::sim::ColourTexture colour = lightstage::sim::parse_colour(text);
    (void)colour.eval(3.0, -4.0);
  } catch (const lightstage::InputError&) {
  }
  return 0;
}
