#pragma once
// A seam for tests: every file the host writes (frames, index files,
// manifests, outputs) goes through one writer, which asks the installed fault
// before writing a file's bytes. A test installs one to play a full disk or a
// failing device in process, without filling a real disk.

#include <filesystem>
#include <functional>

namespace lightstage::io {

// Given the file about to be written (its final path), returns the errno to
// fail that write with (e.g. ENOSPC), or 0 to write it.
using WriteFault = std::function<int(const std::filesystem::path& target)>;

// Installs `fault` for the whole process while it lives (one at a time).
class ScopedWriteFault {
 public:
  explicit ScopedWriteFault(WriteFault fault);
  ~ScopedWriteFault();
  ScopedWriteFault(const ScopedWriteFault&) = delete;
  ScopedWriteFault& operator=(const ScopedWriteFault&) = delete;
};

}  // namespace lightstage::io
