#include "lightstage/pipeline/memory_budget.hpp"

#include "lightstage/common/error.hpp"

#include <fmt/format.h>
#include <unistd.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>

namespace lightstage::pipeline {

void return_free_memory() {
#if defined(__GLIBC__)
  ::malloc_trim(0);
#endif
}

std::size_t physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return std::size_t{4} << 30;  // unknown: a small workstation's
  return static_cast<std::size_t>(pages) * static_cast<std::size_t>(page);
}

std::size_t parse_memory_limit(const std::string& text) {
  if (text == "auto") return physical_memory_bytes() / 2;
  double value = 0;
  const char* begin = text.data();
  const char* end = begin + text.size();
  const auto [next, error] = std::from_chars(begin, end, value);
  double scale = 1;
  if (error == std::errc() && next + 1 == end) {
    switch (std::toupper(static_cast<unsigned char>(*next))) {
      case 'K':
        scale = 1024.0;
        break;
      case 'M':
        scale = 1024.0 * 1024;
        break;
      case 'G':
        scale = 1024.0 * 1024 * 1024;
        break;
      case 'T':
        scale = 1024.0 * 1024 * 1024 * 1024;
        break;
      default:
        scale = 0;
    }
  } else if (error != std::errc() || next != end) {
    scale = 0;
  }
  const double bytes = value * scale;
  if (!(scale > 0) || !(bytes >= 1) || !std::isfinite(bytes) ||
      bytes >= static_cast<double>(std::numeric_limits<std::size_t>::max()))
    fail("--memory-limit: '{}' is not a size (auto, bytes, or a number with K, M, G or T: 256M, 1.5G)", text);
  return static_cast<std::size_t>(bytes);
}

std::string describe_bytes(std::size_t bytes) {
  const auto b = static_cast<double>(bytes);
  if (b >= 1e9) return fmt::format("{:.2f} GB", b / 1e9);
  if (b >= 1e6) return fmt::format("{:.1f} MB", b / 1e6);
  if (b >= 1e3) return fmt::format("{:.1f} kB", b / 1e3);
  return fmt::format("{} B", bytes);
}

}  // namespace lightstage::pipeline
