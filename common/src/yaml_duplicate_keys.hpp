#pragma once
// yaml-cpp keeps both entries of a repeated mapping key and lookups find the
// first, so a second, tighter limit in a rig would be ignored without a word.
// This pass reads the parser's events (aliases are not expanded, so it stays
// linear in the text) and refuses any key repeated within one mapping.

#include <string>

namespace lightstage {

// Throws InputError "source:LINE: duplicate key 'path' (first at line N)".
void refuse_duplicate_yaml_keys(const std::string& yaml_text, const std::string& source);

}  // namespace lightstage
