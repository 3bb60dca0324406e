#include "lightstage/common/printable.hpp"

#include <fmt/format.h>

namespace lightstage {
namespace {

std::string escaped(unsigned char c) {
  switch (c) {
    case '\n':
      return "\\n";
    case '\r':
      return "\\r";
    case '\t':
      return "\\t";
    case '\\':
      return "\\\\";
    default:
      if (c < 0x20 || c == 0x7f) return fmt::format("\\x{:02x}", c);
      return std::string(1, static_cast<char>(c));
  }
}

bool utf8_continuation(unsigned char c) { return (c & 0xc0) == 0x80; }

}  // namespace

std::string printable(std::string_view value, std::size_t max_chars) {
  std::string out;
  std::size_t i = 0;
  for (; i < value.size(); ++i) {
    const std::string piece = escaped(static_cast<unsigned char>(value[i]));
    // Cut before a character that would not fit, and never inside a UTF-8 sequence.
    if (out.size() + piece.size() > max_chars) break;
    out += piece;
  }
  if (i == value.size()) return out;
  while (i > 0 && i < value.size() && utf8_continuation(static_cast<unsigned char>(value[i]))) {
    --i;
    out.pop_back();
  }
  return out + "...";
}

}  // namespace lightstage
