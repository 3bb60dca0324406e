// The text files of a stack folder (filenames.txt, light_directions.txt,
// light_intensities.txt, manifest.json) come from users and other tools. The
// first input byte picks which file of a small valid stack the rest replaces;
// loading must then give a stack or an InputError.
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/stack_io.hpp"

#include "fuzz_scratch.hpp"

#include <opencv2/imgcodecs.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

const std::array<const char*, 4> kFiles = {"filenames.txt", "light_directions.txt", "light_intensities.txt",
                                           "manifest.json"};

void write(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

// A valid three-image 4x4 stack, rewritten before each input.
void write_base_stack(const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  for (const char* name : {"a.png", "b.png", "c.png"}) {
    if (!std::filesystem::exists(dir / name))
      cv::imwrite((dir / name).string(), cv::Mat(4, 4, CV_16UC1, 1000));
  }
  write(dir / "filenames.txt", "a.png\nb.png\nc.png\n");
  write(dir / "light_directions.txt", "0 0 1\n1 0 1\n0 1 1\n");
  write(dir / "light_intensities.txt", "1 1 1\n1 1 1\n1 1 1\n");
  write(dir / "manifest.json", R"({"format": "lightstage-stack", "version": 1, "frames": [
    {"index": 0, "file": "a.png", "led_id": 4}, {"index": 1, "file": "b.png"}, {"index": 2, "file": "c.png"}]})");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const std::filesystem::path dir = lightstage::fuzzing::scratch_dir() / "stack";
  write_base_stack(dir);
  write(dir / kFiles[data[0] % kFiles.size()],
        std::string(reinterpret_cast<const char*>(data + 1), size - 1));
  try {
    lightstage::io::LoadOptions options;
    options.threads = 1;
    (void)lightstage::io::load_stack(dir, options);
  } catch (const lightstage::InputError&) {
  }
  return 0;
}
