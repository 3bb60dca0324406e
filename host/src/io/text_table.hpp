#pragma once
// The small text files of a DiLiGenT-layout stack: one record per line.
// Blank lines are skipped; line numbers in messages are the file's own.

#include "lightstage/common/geometry.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace lightstage::io {

struct TextLine {
  int number = 0;    // 1-based line number in the file
  std::string text;  // without surrounding whitespace
};

// The non-blank lines of a text file; throws InputError naming the file when
// it is missing or unreadable.
std::vector<TextLine> read_text_lines(const std::filesystem::path& path);

struct Vec3Row {
  int number = 0;  // line number
  Vec3 value;
};

// Lines of exactly three finite numbers separated by whitespace (or commas);
// anything else throws InputError "file:line: ...".
std::vector<Vec3Row> read_vec3_rows(const std::filesystem::path& path);

}  // namespace lightstage::io
