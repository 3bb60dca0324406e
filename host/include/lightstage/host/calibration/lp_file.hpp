#pragma once
// RTI light-position files (.lp), as RTIBuilder and relight tools read them:
// the first line holds the number of lights, then one line per light,
// "filename x y z" with a unit direction toward the light. Files with
// Windows paths or CRLF line ends are accepted on reading.

#include "lightstage/common/geometry.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace lightstage::calibration {

struct LpEntry {
  std::string filename;
  Vec3 direction = Vec3::UnitZ();  // unit
};

std::string format_lp(const std::vector<LpEntry>& entries);
// Parses .lp text; `source` names it in messages ("file:line: ..."). Throws
// InputError for a bad count, a count that disagrees with the lines, a
// malformed line or a zero direction.
std::vector<LpEntry> parse_lp(const std::string& text, const std::string& source);
std::vector<LpEntry> read_lp(const std::filesystem::path& path);

}  // namespace lightstage::calibration
