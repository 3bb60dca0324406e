// Depth priors come from sensors and other tools: any 16-bit PNG, PFM, PLY or
// EXR bytes must give a depth map or an InputError. The first byte picks the
// format (0 png, 1 pfm, 2 ply, 3 exr, modulo 4); the rest is the file. EXR
// goes through io/exr.hpp (OpenEXR's header parser and decoder) and the
// loader's checks of the channel and size before any pixel is decoded;
// fuzz_exr covers the reader on its own, at any size.
#include "lightstage/common/error.hpp"
#include "lightstage/host/surface/depth_prior.hpp"

#include "fuzz_scratch.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kExtensions[] = {".png", ".pfm", ".ply", ".exr"};
  const char* ext = kExtensions[data[0] % 4];
  const std::filesystem::path path = lightstage::fuzzing::scratch_dir() / (std::string("depth") + ext);
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
  }
  using lightstage::surface::CameraModel;
  lightstage::Mat3 K;
  K << 40, 0, 7.5, 0, 40, 7.5, 0, 0, 1;
  for (const CameraModel& camera :
       {CameraModel::orthographic(cv::Size(16, 16), 0.5), CameraModel::perspective(cv::Size(16, 16), K)}) {
    try {
      const auto prior = lightstage::surface::load_depth_prior(path, camera);
      if (prior.depth.size() != camera.size || prior.valid.size() != camera.size) __builtin_trap();
    } catch (const lightstage::InputError&) {
    }
  }
  return 0;
}
