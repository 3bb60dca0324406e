#include "lightstage/host/calibration/lp_file.hpp"

#include "lightstage/common/error.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

namespace lightstage::calibration {
namespace {

std::string trim(const std::string& text) {
  const auto begin = text.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos) return "";
  const auto end = text.find_last_not_of(" \t\r\n");
  return text.substr(begin, end - begin + 1);
}

bool parse_number(const std::string& token, double* value) {
  const char* first = token.data();
  const char* last = first + token.size();
  const auto [ptr, ec] = std::from_chars(first, last, *value);
  return ec == std::errc() && ptr == last && std::isfinite(*value);
}

}  // namespace

std::string format_lp(const std::vector<LpEntry>& entries) {
  std::string text = fmt::format("{}\n", entries.size());
  for (const auto& e : entries) {
    text += fmt::format("{} {:.9f} {:.9f} {:.9f}\n", e.filename, e.direction.x(), e.direction.y(),
                        e.direction.z());
  }
  return text;
}

std::vector<LpEntry> parse_lp(const std::string& text, const std::string& source) {
  std::istringstream in(text);
  std::string line;
  int number = 0;
  long long count = -1;
  int count_line = 0;
  std::vector<LpEntry> entries;
  while (std::getline(in, line)) {
    ++number;
    const std::string content = trim(line);
    if (content.empty()) continue;
    if (count < 0) {
      const auto [ptr, ec] = std::from_chars(content.data(), content.data() + content.size(), count);
      if (ec != std::errc() || ptr != content.data() + content.size() || count < 1 || count > 100000)
        fail("{}:{}: the first line must be the number of lights (1..100000), got '{}'", source, number,
             content);
      count_line = number;
      continue;
    }
    // The file name may contain spaces: the last three tokens are the direction.
    std::vector<std::string> tokens;
    std::istringstream words(content);
    for (std::string word; words >> word;) tokens.push_back(word);
    if (tokens.size() < 4) fail("{}:{}: expected 'filename x y z', got '{}'", source, number, content);
    Vec3 direction;
    for (int k = 0; k < 3; ++k) {
      const std::string& token = tokens[tokens.size() - 3 + static_cast<std::size_t>(k)];
      if (!parse_number(token, &direction(k)))
        fail("{}:{}: '{}' is not a finite number (expected 'filename x y z')", source, number, token);
    }
    if (!(direction.norm() > 1e-9)) fail("{}:{}: zero-length light direction", source, number);
    // Cut the three numbers off the end; what remains is the name.
    std::size_t cut = content.size();
    for (std::size_t k = 0; k < 3; ++k) {
      const std::string& token = tokens[tokens.size() - 1 - k];
      cut = content.rfind(token, cut - token.size());
    }
    LpEntry entry;
    entry.filename = trim(content.substr(0, cut));
    entry.direction = direction.normalized();
    entries.push_back(std::move(entry));
    if (static_cast<long long>(entries.size()) > count)
      fail("{}:{}: more lights than the {} announced on line {}", source, number, count, count_line);
  }
  if (count < 0) fail("{}: empty file (expected the number of lights on the first line)", source);
  if (static_cast<long long>(entries.size()) != count)
    fail("{}: {} light line(s), but line {} announces {}", source, entries.size(), count_line, count);
  return entries;
}

std::vector<LpEntry> read_lp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("{}: cannot open for reading", path.string());
  std::ostringstream text;
  text << in.rdbuf();
  return parse_lp(text.str(), path.string());
}

}  // namespace lightstage::calibration
