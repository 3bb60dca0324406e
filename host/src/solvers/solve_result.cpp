#include "lightstage/host/solvers/solve_result.hpp"

#include <fmt/format.h>

#include <cmath>

namespace lightstage {
namespace {

// The facts' texts joined by ", ", skipping the empty ones.
std::string join_texts(const std::vector<SolveFact>& facts) {
  std::string out;
  for (const auto& fact : facts) {
    if (fact.text.empty()) continue;
    if (!out.empty()) out += ", ";
    out += fact.text;
  }
  return out;
}

}  // namespace

cv::Vec3f on_horizon(const cv::Vec3f& n) {
  const float horizontal = std::hypot(n[0], n[1]);
  return horizontal > 1e-6f ? cv::Vec3f(n[0] / horizontal, n[1] / horizontal, 0.f) : cv::Vec3f(0.f, 0.f, 1.f);
}

std::string SolveSummary::format_message() const {
  std::string line = method;
  if (const std::string how = join_texts(settings); !how.empty()) line += " (" + how + ")";
  line += fmt::format(": solved {} of {} pixels in {:.2f} s", pixels_solved, pixels_in_mask, seconds);
  if (const std::string found = join_texts(findings); !found.empty()) line += ", " + found;
  line += fmt::format(" ({} too few observations, {} degenerate)", pixels_rejected_too_few_observations,
                      pixels_rejected_degenerate);
  if (const std::string why = unusable_reason(); !why.empty()) line += "; not usable: " + why;
  return line;
}

std::string SolveSummary::unusable_reason() const {
  if (pixels_in_mask == 0) return "the mask is empty, there was no pixel to solve";
  if (pixels_solved == 0) {
    if (pixels_rejected_degenerate == pixels_in_mask)
      return fmt::format(
          "the lights are degenerate: all {} pixels were rejected as degenerate (near-coplanar lights or "
          "zero solution)",
          pixels_in_mask);
    if (pixels_rejected_too_few_observations == pixels_in_mask)
      return fmt::format("all {} pixels were rejected for too few observations (shadowed or saturated)",
                         pixels_in_mask);
    return fmt::format("no pixel was solved ({} too few observations, {} degenerate)",
                       pixels_rejected_too_few_observations, pixels_rejected_degenerate);
  }
  const double fraction = static_cast<double>(pixels_solved) / static_cast<double>(pixels_in_mask);
  if (fraction < kMinUsableFraction)
    return fmt::format("only {} of {} pixels were solved ({:.2g}%), under the {:.0f}% floor", pixels_solved,
                       pixels_in_mask, 100 * fraction, 100 * kMinUsableFraction);
  return {};
}

nlohmann::json SolveSummary::to_json() const {
  nlohmann::json facts = nlohmann::json::object();
  for (const auto* list : {&settings, &findings})
    for (const auto& fact : *list) facts[fact.key] = fact.value;
  nlohmann::json out = {{"method", method},
                        {"pixels_in_mask", pixels_in_mask},
                        {"pixels_solved", pixels_solved},
                        {"pixels_rejected_too_few_observations", pixels_rejected_too_few_observations},
                        {"pixels_rejected_degenerate", pixels_rejected_degenerate},
                        {"seconds", seconds},
                        {"message", format_message()},
                        {"facts", facts}};
  const std::string why = unusable_reason();
  out["usable"] = why.empty();
  if (!why.empty()) out["unusable_reason"] = why;
  return out;
}

}  // namespace lightstage
