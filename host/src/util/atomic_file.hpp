#pragma once
// Writing files so that a reader never sees half of one: write to a temporary
// name in the same folder (same extension, so format-by-extension writers such
// as cv::imwrite still work), then rename over the target.

#include "lightstage/common/temporary_path.hpp"

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

}  // namespace lightstage::util
