// Camera files come from cameras, tethering programs and raw converters: any
// bytes must give an image (or EXIF) or an InputError. The first byte picks
// the reader: RAW through LibRaw at half size or fully demosaiced
// (io/raw_image.hpp), TIFF through libtiff (io/tiff_image.hpp), the EXIF
// through exiv2 (io/exif.hpp), or JPEG through libjpeg (io/jpeg_image.hpp, as
// read_image reads it); the rest is the file, written under the name the
// reader dispatches on. Seeds (corpus/camera_file): that byte and the DNGs
// (sim/dng_writer.hpp) and TIFFs that test_host_camera_files writes, and
// baseline, progressive and grey JPEGs.
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/exif.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/jpeg_image.hpp"
#include "lightstage/host/io/raw_image.hpp"
#include "lightstage/host/io/tiff_image.hpp"

#include "fuzz_scratch.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

// Larger declared images are valid but cost gigabytes; the readers' own limits
// are covered by the unit tests.
constexpr int kMaxFuzzedPixels = 2048 * 2048;

std::filesystem::path scratch(const char* extension) {
  return lightstage::fuzzing::scratch_dir() / (std::string("camera") + extension);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  namespace io = lightstage::io;
  const int kind = data[0] % 5;
  const std::filesystem::path path = scratch(kind == 2 ? ".tif" : kind >= 3 ? ".jpg" : ".dng");
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
  }
  try {
    switch (kind) {
      case 0:
      case 1: {
        const auto demosaic = kind == 0 ? io::RawDemosaic::half : io::RawDemosaic::full;
        const cv::Size declared = io::read_raw_size(path, demosaic);
        if (declared.area() > kMaxFuzzedPixels) break;
        const io::RawImage raw = io::read_raw(path, demosaic);
        if (raw.image.empty() || raw.image.depth() != CV_16U) __builtin_trap();
        (void)raw.describe().dump();
        break;
      }
      case 2: {
        const cv::Size declared = io::read_tiff_size(path);
        if (declared.area() > kMaxFuzzedPixels) break;
        const cv::Mat image = io::read_tiff(path);
        if (image.size() != declared) __builtin_trap();
        break;
      }
      case 4: {
        const cv::Size declared = io::read_jpeg_size(path);
        if (declared.area() > kMaxFuzzedPixels) break;
        const cv::Mat image = io::read_image(path);
        if (image.size() != declared || image.depth() != CV_8U) __builtin_trap();
        break;
      }
      default: {
        const io::ExifInfo exif = io::read_exif(path);
        (void)exif.to_json().dump();
        if (exif.orientation && (*exif.orientation < 1 || *exif.orientation > 8)) __builtin_trap();
        // The time a stills camera's shot is matched by: a second's worth of steps at most.
        if (const auto time = io::taken_time(exif);
            time && (time->resolution_ns < 1 || time->resolution_ns > 1'000'000'000))
          __builtin_trap();
      }
    }
  } catch (const lightstage::InputError&) {
  }
  return 0;
}
