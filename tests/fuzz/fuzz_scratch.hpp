#pragma once
// A folder of the fuzzing process's own for the files a target writes its input into: made on
// first use, removed with all it holds when the process exits (runs end with exit(), crashes
// keep it for the post-mortem).

#include <unistd.h>

#include <filesystem>
#include <string>
#include <system_error>

namespace lightstage::fuzzing {

inline const std::filesystem::path& scratch_dir() {
  struct Folder {
    std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("lightstage-fuzz-" + std::to_string(getpid()));
    Folder() { std::filesystem::create_directories(path); }
    ~Folder() {
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  };
  static const Folder folder;
  return folder.path;
}

}  // namespace lightstage::fuzzing
