#include "lightstage/pipeline/decode_floor.hpp"

#include "lightstage/common/parallel.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/stack_io.hpp"

#include <atomic>
#include <chrono>

namespace lightstage::pipeline {

nlohmann::json DecodeFloor::to_json() const {
  return {{"seconds", seconds}, {"frames", frames}, {"decoded_bytes", decoded_bytes}, {"threads", threads}};
}

DecodeFloor measure_decode_floor(const std::filesystem::path& stack, int threads) {
  io::LoadOptions index;
  index.frame_pixels = false;
  index.load_ground_truth = false;
  const ImageStack frames = io::load_stack(stack, index);
  DecodeFloor floor;
  floor.frames = frames.frames.size();
  floor.threads = resolve_threads(threads);
  std::atomic<std::size_t> bytes{0};
  const auto start = std::chrono::steady_clock::now();
  parallel_for(static_cast<int>(frames.frames.size()), threads, [&](int i) {
    const cv::Mat image = io::read_image(stack / frames.frames[static_cast<std::size_t>(i)].filename);
    bytes += image.total() * image.elemSize();
  });
  floor.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  floor.decoded_bytes = bytes;
  return floor;
}

}  // namespace lightstage::pipeline
