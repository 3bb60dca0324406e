#pragma once
// Writing files so that a reader never sees half of one: write to a temporary
// name in the same folder (same extension, so format-by-extension writers such
// as cv::imwrite still work), then rename over the target.

#include "lightstage/common/temporary_path.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace lightstage::util {

// Temporary names: lightstage::temporary_sibling (common/temporary_path.hpp).

// Renames `temporary` to `target`; on failure removes `temporary` and throws
// InputError naming `target`.
void commit_temporary(const std::filesystem::path& temporary, const std::filesystem::path& target);

// Writes `bytes` to a fresh temporary sibling of `target` (io/write_fault.hpp
// may fail it) and returns its name; the caller commits or removes it. On
// failure nothing is left behind and it throws, naming `target`: Error for a
// full disk or quota ("no space left on the device", not the path's fault),
// InputError otherwise (a folder that is missing or not writable).
std::filesystem::path write_temporary(const std::filesystem::path& target, std::string_view bytes);

// Writes `text` to `path` atomically; throws as write_temporary.
void write_text_atomic(const std::filesystem::path& path, std::string_view text);

// A file written in parts as they are made (an image's rows, band by band)
// into a temporary sibling of `target`: commit() renames it over `target`;
// destroyed uncommitted, it is removed. Throws as write_temporary.
class TemporaryFile {
 public:
  explicit TemporaryFile(std::filesystem::path target);
  ~TemporaryFile();
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;

  const std::filesystem::path& target() const { return target_; }
  // `bytes` at `offset` (the file grows as needed), or after the furthest byte written.
  void write_at(std::uint64_t offset, std::string_view bytes);
  void append(std::string_view bytes) { write_at(end_, bytes); }
  std::uint64_t end() const { return end_; }
  // Closes the file and renames it over target().
  void commit();

 private:
  void close_and_remove();

  std::filesystem::path target_, temporary_;
  int fd_ = -1;
  int failed_ = 0;  // the errno of a failed write (OpenEXR swallows errors in its destructor)
  std::uint64_t end_ = 0;
};

}  // namespace lightstage::util
