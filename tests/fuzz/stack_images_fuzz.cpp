// Image files in a stack folder come from users and other tools. The first
// input byte picks which file of a small valid stack the rest replaces (the
// second PNG frame, the mask, or the second frame of a PFM stack); loading
// reads its header, checks it against the first frame, then decodes it, and
// must give a stack or an InputError. The first frame is never replaced, so
// no input can make the loader decode more than a 4x4 image.
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/stack_io.hpp"

#include "fuzz_scratch.hpp"

#include <opencv2/imgcodecs.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

namespace fs = std::filesystem;

void write(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes;
}

// Three 4x4 frames named a/b/c.<extension>, directions, and a manifest declaring 4x4.
void write_base_stack(const fs::path& dir, const std::string& extension) {
  fs::create_directories(dir);
  for (const char* stem : {"a", "b", "c"}) {
    const fs::path path = dir / (stem + extension);
    if (extension == ".pfm") {
      lightstage::io::write_pfm(path, cv::Mat(4, 4, CV_32FC1, cv::Scalar::all(0.25)));
    } else {
      cv::imwrite(path.string(), cv::Mat(4, 4, CV_16UC1, cv::Scalar::all(1000)));
    }
  }
  write(dir / "filenames.txt", "a" + extension + "\nb" + extension + "\nc" + extension + "\n");
  write(dir / "light_directions.txt", "0 0 1\n1 0 1\n0 1 1\n");
  write(dir / "manifest.json", R"({"format": "lightstage-stack", "version": 1, "width": 4, "height": 4})");
  fs::remove(dir / "mask.png");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const fs::path root = lightstage::fuzzing::scratch_dir();
  const std::string bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  const int choice = data[0] % 3;
  const fs::path dir = root / (choice == 2 ? "pfm" : "png");
  write_base_stack(dir, choice == 2 ? ".pfm" : ".png");
  write(dir / (choice == 0 ? "b.png" : choice == 1 ? "mask.png" : "b.pfm"), bytes);
  try {
    const lightstage::ImageStack stack = lightstage::io::load_stack(dir);
    (void)cv::sum(stack.frames[1].image);
  } catch (const lightstage::InputError&) {
  }
  return 0;
}
