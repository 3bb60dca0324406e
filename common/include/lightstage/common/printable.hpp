#pragma once
// Values from outside input shown in error messages: a message stays one
// short line whatever the file held. Control characters are escaped (\n, \t,
// \x1b, ...) so a terminal shows them instead of obeying them, and anything
// past `max_chars` is cut and marked with "...".

#include <cstddef>
#include <string>
#include <string_view>

namespace lightstage {

inline constexpr std::size_t kPrintableChars = 80;

std::string printable(std::string_view value, std::size_t max_chars = kPrintableChars);

}  // namespace lightstage
