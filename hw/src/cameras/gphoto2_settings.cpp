#include "gphoto2_settings.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>

namespace lightstage::hw::gphoto2 {

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

bool starts_with_ci(std::string_view s, std::string_view prefix) {
  return s.size() >= prefix.size() && lower(s.substr(0, prefix.size())) == prefix;
}

// A whole non-negative decimal number ("0.3", "30", "5.6"), nothing else.
std::optional<double> number(std::string_view s) {
  if (s.empty() || !(std::isdigit(static_cast<unsigned char>(s.front())) || s.front() == '.'))
    return std::nullopt;
  double value = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

// The name lists; Canon and Nikon (ptp2) use the first names, older Nikons
// the "2" variants, Sony and Fujifilm the later ones.
constexpr std::array<std::string_view, 3> kShutterNames = {"shutterspeed", "shutterspeed2", "exposuretime"};
constexpr std::array<std::string_view, 2> kIsoNames = {"iso", "isospeed"};
constexpr std::array<std::string_view, 2> kApertureNames = {"aperture", "f-number"};
constexpr std::array<std::string_view, 2> kFormatNames = {"imageformat", "imagequality"};
constexpr std::array<std::string_view, 1> kCaptureTargetNames = {"capturetarget"};

}  // namespace

std::string_view to_string(Setting setting) {
  switch (setting) {
    case Setting::kShutter:
      return "shutter speed";
    case Setting::kIso:
      return "ISO";
    case Setting::kAperture:
      return "aperture";
    case Setting::kImageFormat:
      return "image format";
    case Setting::kCaptureTarget:
      return "capture target";
  }
  return "setting";
}

std::span<const std::string_view> widget_names(Setting setting) {
  switch (setting) {
    case Setting::kShutter:
      return kShutterNames;
    case Setting::kIso:
      return kIsoNames;
    case Setting::kAperture:
      return kApertureNames;
    case Setting::kImageFormat:
      return kFormatNames;
    case Setting::kCaptureTarget:
      return kCaptureTargetNames;
  }
  return {};
}

std::optional<double> parse_shutter_us(std::string_view text) {
  std::string_view s = trim(text);
  // Units and the seconds mark: "1/125s", "2 sec", "30\"" all mean seconds.
  for (std::string_view suffix : {std::string_view("sec"), std::string_view("s"), std::string_view("\"")}) {
    if (s.size() > suffix.size() && lower(s.substr(s.size() - suffix.size())) == suffix) {
      s = trim(s.substr(0, s.size() - suffix.size()));
      break;
    }
  }
  if (const auto slash = s.find('/'); slash != std::string_view::npos) {
    const auto num = number(trim(s.substr(0, slash)));
    const auto den = number(trim(s.substr(slash + 1)));
    if (!num || !den || *den <= 0 || *num <= 0) return std::nullopt;
    return *num / *den * 1e6;
  }
  // "1\"3": the camera's display for 1.3 s.
  if (const auto mark = s.find('"'); mark != std::string_view::npos) {
    const std::string_view whole = s.substr(0, mark);
    const std::string_view tenths = s.substr(mark + 1);
    if (whole.empty() || tenths.empty() ||
        !std::all_of(whole.begin(), whole.end(),
                     [](char c) { return std::isdigit(static_cast<unsigned char>(c)); }) ||
        !std::all_of(tenths.begin(), tenths.end(),
                     [](char c) { return std::isdigit(static_cast<unsigned char>(c)); })) {
      return std::nullopt;
    }
    const auto seconds = number(fmt::format("{}.{}", whole, tenths));
    if (!seconds || *seconds <= 0) return std::nullopt;
    return *seconds * 1e6;
  }
  const auto seconds = number(s);
  if (!seconds || *seconds <= 0) return std::nullopt;
  return *seconds * 1e6;
}

std::optional<double> parse_f_number(std::string_view text) {
  std::string_view s = trim(text);
  if (starts_with_ci(s, "f/")) {
    s.remove_prefix(2);
  } else if (starts_with_ci(s, "f")) {
    s.remove_prefix(1);
  }
  const auto value = number(trim(s));
  if (!value || *value <= 0) return std::nullopt;
  return value;
}

std::optional<double> parse_iso(std::string_view text) {
  std::string_view s = trim(text);
  if (starts_with_ci(s, "iso")) s = trim(s.substr(3));
  const auto value = number(s);
  if (!value || *value <= 0) return std::nullopt;
  return value;
}

double max_log2_ratio(Setting setting) {
  // Half a stop of exposure either way: cameras offer third stops, so any
  // value inside the offered range is within a sixth of a stop of a choice.
  return setting == Setting::kAperture ? 0.25 : 0.5;
}

std::optional<std::size_t> nearest_choice(const std::vector<std::string>& choices, double wanted,
                                          std::optional<double> (*parse)(std::string_view), double max_log2) {
  if (!(wanted > 0) || !std::isfinite(wanted)) return std::nullopt;
  std::optional<std::size_t> best;
  double best_distance = 0;
  for (std::size_t i = 0; i < choices.size(); ++i) {
    const auto value = parse(choices[i]);
    if (!value) continue;
    const double distance = std::abs(std::log2(*value / wanted));
    if (!best || distance < best_distance) {
      best = i;
      best_distance = distance;
    }
  }
  if (best && best_distance > max_log2 + 1e-9) return std::nullopt;
  return best;
}

std::optional<std::size_t> choice_by_name(const std::vector<std::string>& choices, std::string_view wanted) {
  const std::string want = lower(trim(wanted));
  if (want.empty()) return std::nullopt;
  std::optional<std::size_t> best;
  for (std::size_t i = 0; i < choices.size(); ++i) {
    const std::string name = lower(choices[i]);
    if (name == want) return i;
    if (name.find(want) != std::string::npos && (!best || choices[i].size() < choices[*best].size()))
      best = i;
  }
  return best;
}

std::optional<std::size_t> memory_card_choice(const std::vector<std::string>& choices) {
  return choice_by_name(choices, "card");
}

std::string describe_choices(const std::vector<std::string>& choices) {
  if (choices.empty()) return "none";
  constexpr std::size_t kShown = 6;
  std::string text;
  auto add = [&](const std::string& c) { text += (text.empty() ? "" : ", ") + c; };
  if (choices.size() <= 2 * kShown) {
    for (const auto& c : choices) add(c);
    return text;
  }
  for (std::size_t i = 0; i < kShown; ++i) add(choices[i]);
  text += ", ...";
  for (std::size_t i = choices.size() - kShown; i < choices.size(); ++i) add(choices[i]);
  return text;
}

std::string describe_shutter_us(double us) {
  if (us > 0 && us < 1e6) {
    const double denominator = 1e6 / us;
    if (std::abs(denominator - std::round(denominator)) < 0.01 * denominator)
      return fmt::format("1/{} s", std::round(denominator));
  }
  return fmt::format("{:g} s", us / 1e6);
}

}  // namespace lightstage::hw::gphoto2
