#pragma once
// Text fields of camera files (EXIF Make and Model, a RAW file's camera name)
// are ASCII by their specifications but hold whatever a camera or a damaged
// file put there. Before they reach a manifest (JSON, UTF-8) every byte
// outside printable ASCII becomes '?', and trailing NULs and spaces go.

#include <string>
#include <string_view>

namespace lightstage::io {

inline std::string ascii_text(std::string_view bytes) {
  while (!bytes.empty() && (bytes.back() == '\0' || bytes.back() == ' ')) bytes.remove_suffix(1);
  std::string text;
  text.reserve(bytes.size());
  for (const char c : bytes) text += c >= 0x20 && c <= 0x7e ? c : '?';
  return text;
}

}  // namespace lightstage::io
