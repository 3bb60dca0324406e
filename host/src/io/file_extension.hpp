#pragma once
// A file's extension as readers dispatch on it: lower case, with its dot (".png").

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

namespace lightstage::io {

inline std::string lower_extension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

}  // namespace lightstage::io
