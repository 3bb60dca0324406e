#include "lightstage/sim/gpio/fault.hpp"

#include "lightstage/common/error.hpp"

#include <charconv>

namespace lightstage::sim::gpio {
namespace {

constexpr const char* kForms = "lose-strobe:N, stuck:LINE or drop-connection:N";

int positive_count(const std::string& text, const std::string& arg) {
  int value = 0;
  const char* end = arg.data() + arg.size();
  const auto [ptr, ec] = std::from_chars(arg.data(), end, value);
  if (arg.empty() || ec != std::errc() || ptr != end || value < 1) {
    fail("fault '{}': '{}' is not a count of 1 or more", text, arg);
  }
  return value;
}

}  // namespace

Fault parse_fault(const std::string& text) {
  const auto colon = text.find(':');
  const std::string kind = text.substr(0, colon);
  const std::string arg = colon == std::string::npos ? "" : text.substr(colon + 1);
  Fault fault;
  fault.text = text;
  if (kind == "lose-strobe") {
    fault.kind = Fault::Kind::kLoseStrobe;
    fault.count = positive_count(text, arg);
  } else if (kind == "drop-connection") {
    fault.kind = Fault::Kind::kDropConnection;
    fault.count = positive_count(text, arg);
  } else if (kind == "stuck") {
    fault.kind = Fault::Kind::kStuck;
    if (arg.empty()) fail("fault '{}': stuck needs a line name or offset (stuck:LED5)", text);
    fault.line = arg;
  } else {
    fail("fault '{}': unknown kind '{}'; expected {}", text, kind, kForms);
  }
  return fault;
}

}  // namespace lightstage::sim::gpio
