#include "io/text_table.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/printable.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <system_error>

namespace lightstage::io {
namespace {

std::string trim(const std::string& text) {
  std::size_t begin = 0, end = text.size();
  while (begin < end && std::isspace(static_cast<unsigned char>(text[begin]))) ++begin;
  while (end > begin && std::isspace(static_cast<unsigned char>(text[end - 1]))) --end;
  return text.substr(begin, end - begin);
}

}  // namespace

std::vector<TextLine> read_text_lines(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) fail("{}: no such file", path.string());
  std::ifstream in(path);
  if (!in) fail("{}: cannot open for reading", path.string());
  std::vector<TextLine> lines;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    auto text = trim(line);
    if (!text.empty()) lines.push_back({number, std::move(text)});
  }
  if (in.bad()) fail("{}: read error", path.string());
  return lines;
}

std::vector<Vec3Row> read_vec3_rows(const std::filesystem::path& path) {
  std::vector<Vec3Row> rows;
  for (const auto& line : read_text_lines(path)) {
    std::string text = line.text;
    for (char& c : text) {
      if (c == ',') c = ' ';
    }
    Vec3 value;
    int count = 0;
    const char* p = text.data();
    const char* end = text.data() + text.size();
    bool malformed = false;
    while (p < end) {
      while (p < end && std::isspace(static_cast<unsigned char>(*p))) ++p;
      if (p == end) break;
      double number = 0;
      if (*p == '+') ++p;  // from_chars does not accept a leading '+'
      const auto [next, ec] = std::from_chars(p, end, number);
      if (ec != std::errc() || (next < end && !std::isspace(static_cast<unsigned char>(*next))) ||
          !std::isfinite(number)) {
        malformed = true;
        break;
      }
      if (count < 3) value[count] = number;
      ++count;
      p = next;
    }
    if (malformed || count != 3) {
      fail("{}:{}: expected three numbers 'a b c', got '{}'", path.string(), line.number,
           printable(line.text));
    }
    rows.push_back({line.number, value});
  }
  return rows;
}

}  // namespace lightstage::io
