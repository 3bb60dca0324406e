#include "util/atomic_file.hpp"

#include "lightstage/common/error.hpp"

#include <unistd.h>

#include <atomic>
#include <fstream>
#include <system_error>

namespace lightstage::util {

std::filesystem::path temporary_sibling(const std::filesystem::path& target) {
  static std::atomic<unsigned> counter{0};
  const auto name = fmt::format(".{}.tmp-{}-{}{}", target.filename().string(), getpid(), counter++,
                                target.extension().string());
  return target.parent_path() / name;
}

void commit_temporary(const std::filesystem::path& temporary, const std::filesystem::path& target) {
  std::error_code error;
  std::filesystem::rename(temporary, target, error);
  if (error) {
    std::filesystem::remove(temporary, error);
    fail("{}: cannot write: {}", target.string(), error.message());
  }
}

void write_text_atomic(const std::filesystem::path& path, const std::string& text) {
  const auto temporary = temporary_sibling(path);
  {
    std::ofstream out(temporary, std::ios::binary);
    if (!out) fail("{}: cannot write: cannot create a file in this folder", path.string());
    out << text;
    out.flush();
    if (!out) {
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      fail("{}: cannot write: write error", path.string());
    }
  }
  commit_temporary(temporary, path);
}

}  // namespace lightstage::util
