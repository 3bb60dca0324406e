// A result folder's summary.json may come from anywhere (another version, a
// hand edit, a copied folder): the report reads its per-light statistics
// back for a stack's frames. Any text gives them, consistent with the frames,
// or nothing, never a crash.
#include "lightstage/common/image_stack.hpp"
#include "lightstage/host/report/light_statistics.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

namespace {

lightstage::ImageStack three_frames() {
  lightstage::ImageStack stack;
  for (const char* file : {"001.png", "002.png", "003.png"}) {
    lightstage::Frame frame;
    frame.filename = file;
    stack.frames.push_back(frame);
  }
  return stack;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const lightstage::ImageStack stack = three_frames();
  const nlohmann::json recorded =
      nlohmann::json::parse(reinterpret_cast<const char*>(data), reinterpret_cast<const char*>(data) + size,
                            nullptr, /*allow_exceptions=*/false);
  const auto stats = lightstage::report::recorded_light_statistics(recorded, stack);
  if (!stats) return 0;
  if (stats->size() != stack.frames.size() || !lightstage::report::recorded_threshold(recorded)) std::abort();
  for (std::size_t i = 0; i < stats->size(); ++i) {
    const auto& s = (*stats)[i];
    if (s.file != stack.frames[i].filename || !std::isfinite(s.mean_value) || !std::isfinite(s.shadow_share))
      std::abort();
  }
  return 0;
}
