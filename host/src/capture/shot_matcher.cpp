#include "lightstage/host/capture/shot_matcher.hpp"

#include <algorithm>
#include <limits>
#include <numeric>
#include <set>
#include <utility>

namespace lightstage {
namespace {

using Pairs = std::vector<std::pair<std::size_t, std::size_t>>;  // (file, step), both in time order

// The largest order-keeping matching of files to steps among the allowed
// pairs (a longest common subsequence), optionally without one pair.
Pairs largest_matching(const std::vector<std::vector<bool>>& allowed,
                       std::optional<std::pair<std::size_t, std::size_t>> forbidden = std::nullopt) {
  const std::size_t nf = allowed.size(), ns = nf ? allowed[0].size() : 0;
  std::vector<std::vector<int>> best(nf + 1, std::vector<int>(ns + 1, 0));
  const auto ok = [&](std::size_t f, std::size_t s) { return allowed[f][s] && forbidden != std::pair{f, s}; };
  for (std::size_t f = nf; f-- > 0;) {
    for (std::size_t s = ns; s-- > 0;) {
      best[f][s] = std::max(best[f + 1][s], best[f][s + 1]);
      if (ok(f, s)) best[f][s] = std::max(best[f][s], 1 + best[f + 1][s + 1]);
    }
  }
  Pairs pairs;
  for (std::size_t f = 0, s = 0; f < nf && s < ns;) {
    if (ok(f, s) && best[f][s] == 1 + best[f + 1][s + 1]) {
      pairs.emplace_back(f, s);
      ++f, ++s;
    } else if (best[f][s] == best[f + 1][s]) {
      ++f;
    } else {
      ++s;
    }
  }
  return pairs;
}

// Whether another matching as large exists: one without one of its pairs.
bool has_rival(const std::vector<std::vector<bool>>& allowed, const Pairs& pairs) {
  return std::ranges::any_of(
      pairs, [&](const auto& pair) { return largest_matching(allowed, pair).size() == pairs.size(); });
}

}  // namespace

ShotMatch match_shots(const std::vector<StepTiming>& steps, const std::vector<ShotTiming>& shots,
                      const ShotMatchOptions& options) {
  ShotMatch match;
  match.frame_of_step.assign(steps.size(), std::nullopt);
  std::vector<std::size_t> step_order(steps.size()), shot_order(shots.size());
  std::iota(step_order.begin(), step_order.end(), 0);
  std::iota(shot_order.begin(), shot_order.end(), 0);
  std::ranges::stable_sort(step_order, {}, [&](std::size_t i) { return steps[i].trigger_ns; });
  // By stamp when files have one: a file without (a foreign one) is then matched to nothing.
  const auto has_stamp = [](const ShotTiming& s) { return s.resolution_ns > 0; };
  const bool stamped = std::ranges::any_of(shots, has_stamp);
  // The order taken: by stamp when every file has one, else by arrival.
  std::ranges::stable_sort(shot_order, {}, [&](std::size_t i) {
    if (!stamped) return std::pair{shots[i].arrived_ns, std::int64_t{0}};
    return std::pair{has_stamp(shots[i]) ? shots[i].stamp_ns : std::numeric_limits<std::int64_t>::max(),
                     shots[i].arrived_ns};
  });
  const std::size_t nf = shots.size(), ns = steps.size();
  const auto shot = [&](std::size_t f) -> const ShotTiming& { return shots[shot_order[f]]; };
  const auto step = [&](std::size_t s) -> const StepTiming& { return steps[step_order[s]]; };
  const auto arrives_in_time = [&](std::size_t f, std::size_t s) {
    const std::int64_t exposure_end =
        step(s).trigger_ns + static_cast<std::int64_t>(step(s).exposure_us * 1000);
    if (shot(f).arrived_ns < exposure_end) return false;
    return options.arrival_timeout_ns <= 0 ||
           shot(f).arrived_ns <= exposure_end + options.max_lag_ns + options.arrival_timeout_ns;
  };
  const auto residual = [&](std::size_t f, std::size_t s) { return shot(f).stamp_ns - step(s).trigger_ns; };

  // Windows to try: without stamps, only arrival times and order count.
  std::set<std::int64_t> windows;
  const std::int64_t resolution =
      stamped ? std::ranges::max(shots, {}, &ShotTiming::resolution_ns).resolution_ns : 0;
  std::int64_t width = 0;
  if (stamped) {
    width = options.max_lag_ns + resolution;
    for (std::size_t f = 0; f < nf; ++f) {
      for (std::size_t s = 0; s < ns; ++s) {
        if (has_stamp(shot(f)) && arrives_in_time(f, s)) windows.insert(residual(f, s));
      }
    }
  } else {
    windows.insert(0);
  }
  struct Candidate {
    Pairs pairs;
    std::vector<std::vector<bool>> allowed;
    std::int64_t window = 0;
  };
  std::vector<Candidate> best;
  for (const std::int64_t c : windows) {
    std::vector<std::vector<bool>> allowed(nf, std::vector<bool>(ns, false));
    for (std::size_t f = 0; f < nf; ++f) {
      for (std::size_t s = 0; s < ns; ++s) {
        allowed[f][s] =
            arrives_in_time(f, s) &&
            (!stamped || (has_stamp(shot(f)) && residual(f, s) >= c && residual(f, s) <= c + width));
      }
    }
    Pairs pairs = largest_matching(allowed);
    if (pairs.empty()) continue;
    if (!best.empty() && pairs.size() < best.front().pairs.size()) continue;
    if (!best.empty() && pairs.size() > best.front().pairs.size()) best.clear();
    // The same files on the same steps through another window is the same matching.
    if (std::ranges::any_of(best, [&](const Candidate& b) { return b.pairs == pairs; })) continue;
    best.push_back({std::move(pairs), std::move(allowed), c});
  }
  // The mean stamp-minus-trigger of a matching: the camera clock's offset plus the mean shutter lag.
  const auto mean_residual = [&](const Pairs& pairs) {
    long double sum = 0;
    for (const auto& [f, s] : pairs) sum += static_cast<long double>(residual(f, s));
    return static_cast<std::int64_t>(sum / static_cast<long double>(pairs.size()));
  };
  if (best.size() > 1 && options.clock_offset_ns) {
    // An earlier batch's offset picks the matching nearest to it: a file
    // filed one step off is a whole step's spacing away, the lag's jitter
    // averages out over the batch.
    const auto distance = [&](const Candidate& b) {
      return std::abs(mean_residual(b.pairs) - *options.clock_offset_ns);
    };
    std::ranges::sort(best, {}, distance);
    if (distance(best[1]) - distance(best[0]) > 2 * resolution) best.resize(1);
  }
  const bool unique = best.size() == 1 && !has_rival(best[0].allowed, best[0].pairs);
  if (!best.empty() && !unique) match.ambiguous = true;
  std::vector<bool> used(nf, false);
  if (unique) {
    for (const auto& [f, s] : best[0].pairs) {
      match.frame_of_step[step_order[s]] = shot_order[f];
      used[f] = true;
    }
    if (stamped) match.clock_offset_ns = mean_residual(best[0].pairs);
  }
  for (std::size_t f = 0; f < nf; ++f) {
    if (!used[f]) match.unmatched_frames.push_back(shot_order[f]);
  }
  std::ranges::sort(match.unmatched_frames);
  return match;
}

}  // namespace lightstage
