#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

namespace lightstage::testing {

std::filesystem::path source_dir() {
  if (const char* dir = std::getenv("LIGHTSTAGE_SOURCE_DIR")) return dir;
  return LIGHTSTAGE_TEST_SOURCE_DIR;
}

std::filesystem::path shared_data_dir() {
  if (const char* dir = std::getenv("LIGHTSTAGE_SHARED_DATA")) return dir;
  const auto candidate = source_dir().parent_path() / "shared" / "data";
  return std::filesystem::exists(candidate) ? candidate : std::filesystem::path();
}

std::filesystem::path scratch_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  // Outside a test (a suite's SetUpTestSuite), one folder per suite and process:
  // CTest runs a suite's cases as separate processes, in parallel.
  const auto* suite = ::testing::UnitTest::GetInstance()->current_test_suite();
  std::string name = info    ? std::string(info->test_suite_name()) + "." + info->name()
                     : suite ? std::string(suite->name()) + ".setup-" + std::to_string(::getpid())
                             : "scratch-" + std::to_string(::getpid());
  for (char& c : name) {
    if (c == '/') c = '_';
  }
  const auto dir = std::filesystem::path(LIGHTSTAGE_TEST_BINARY_DIR) / "scratch" / name;
  // Emptied on the first call of each test only: a test (and the fixtures it
  // starts) may ask again and must find what it wrote.
  static std::string prepared;
  if (prepared != name) {
    std::filesystem::remove_all(dir);
    prepared = name;
  }
  std::filesystem::create_directories(dir);
  return dir;
}

std::filesystem::path socket_dir() {
  // One folder per test process, removed when it exits; /tmp keeps the paths short.
  // Never destroyed, so the atexit handler can still read it.
  static const auto* const dir = [] {
    std::string pattern = (std::filesystem::temp_directory_path() / "lightstage-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    auto* path = new std::filesystem::path(pattern);
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(socket_dir(), ignored);
    });
    return path;
  }();
  return *dir;
}

std::filesystem::path bin_dir() { return std::filesystem::path(LIGHTSTAGE_TEST_BINARY_DIR) / "bin"; }

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace lightstage::testing
