#include "lightstage/common/temporary_path.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <atomic>

namespace lightstage {

std::filesystem::path temporary_sibling(const std::filesystem::path& target) {
  static std::atomic<unsigned> counter{0};
  const auto name = fmt::format(".{}.tmp-{}-{}{}", target.filename().string(), getpid(), counter++,
                                target.extension().string());
  return target.parent_path() / name;
}

}  // namespace lightstage
