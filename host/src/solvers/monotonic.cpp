#include "lightstage/host/solvers/monotonic.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/geometry.hpp"
#include "solvers/pixel_driver.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

namespace lightstage {

void MonotonicOptions::check() const {
  detail::check_shadow_threshold("MonotonicOptions", shadow_threshold);
  if (!(infinity > 1 && std::isfinite(infinity)))
    fail("MonotonicOptions.infinity: must be > 1, got {}", infinity);
  if (!(gamma > 0 && gamma <= 20))
    fail("MonotonicOptions.gamma (--gamma): must be in (0, 20], got {}", gamma);
  if (!(coarse_step_deg > 0 && coarse_step_deg <= 10))
    fail("MonotonicOptions.coarse_step_deg: must be in (0, 10], got {}", coarse_step_deg);
  if (!(fine_step_deg > 0 && fine_step_deg <= coarse_step_deg))
    fail("MonotonicOptions.fine_step_deg: must be in (0, coarse_step_deg], got {}", fine_step_deg);
  detail::check_min_observations("MonotonicOptions", min_observations);
  if (!(plateau_tolerance >= 0 && plateau_tolerance <= 100))
    fail("MonotonicOptions.plateau_tolerance (--plateau-tolerance): must be in [0, 100], got {}",
         plateau_tolerance);
  if (!(refine_step_deg >= 0 && refine_step_deg <= 20))
    fail("MonotonicOptions.refine_step_deg: must be in [0, 20], got {}", refine_step_deg);
  if (ring_quantiles.empty()) fail("MonotonicOptions.ring_quantiles: needs at least one ring");
  for (const double q : ring_quantiles) {
    if (!(q >= 0 && q <= 1)) fail("MonotonicOptions.ring_quantiles: each must be in [0, 1], got {}", q);
  }
  if (ring_samples < 8 || ring_samples % 2 != 0)
    fail("MonotonicOptions.ring_samples: must be even and at least 8, got {}", ring_samples);
  if (ring_neighbours < 1)
    fail("MonotonicOptions.ring_neighbours: must be at least 1, got {}", ring_neighbours);
  detail::check_threads("MonotonicOptions", threads);
}

nlohmann::json MonotonicOptions::to_json() const {
  return {{"shadow_threshold", shadow_threshold},
          {"infinity", infinity},
          {"gamma", gamma},
          {"coarse_step_deg", coarse_step_deg},
          {"fine_step_deg", fine_step_deg},
          {"plateau_tolerance", plateau_tolerance},
          {"refine_step_deg", refine_step_deg},
          {"min_observations", min_observations},
          {"ring_quantiles", ring_quantiles},
          {"ring_samples", ring_samples},
          {"ring_neighbours", ring_neighbours},
          {"drop_saturated", drop_saturated},
          {"threads", threads}};
}

void prepare_monotonic(const PixelObservations& pixel, MonotonicWorkspace& ws) {
  ws.lights.clear();
  ws.halves.clear();
  ws.values.clear();
  for (Eigen::Index j = 0; j < pixel.count(); ++j) {
    if (!pixel.usable[static_cast<std::size_t>(j)]) continue;
    const Eigen::Vector3d l = pixel.lights.row(j).transpose();
    ws.lights.push_back(l);
    ws.halves.push_back(half_vector(l));
    ws.values.push_back(pixel.values(j));
  }
  const std::size_t m = ws.values.size();
  ws.x.resize(m);
  ws.y.resize(m);
  ws.order.resize(m);
  for (std::size_t k = 0; k < m; ++k) ws.order[k] = static_cast<int>(k);
}

double monotonicity_cost(const Eigen::Vector3d& n, const MonotonicOptions& options, MonotonicWorkspace& ws) {
  const double i0 = options.shadow_threshold;
  const bool gamma5 = options.gamma == 5.0;
  const std::size_t m = ws.values.size();
  for (std::size_t k = 0; k < m; ++k) {
    const double value = ws.values[k];
    const double d = ws.lights[k].dot(n);
    double y;
    if (value <= i0) {
      y = i0;  // a shadow: the lowest possible reflectance
    } else if (d <= 0) {
      y = options.infinity;  // lit, yet the hypothesis puts the light behind the surface
    } else {
      y = value / d;
    }
    if (gamma5) {
      const double y2 = y * y;
      ws.y[k] = y2 * y2 * y;
    } else {
      ws.y[k] = std::pow(y, options.gamma);
    }
    ws.x[k] = ws.halves[k].dot(n);
  }
  // Insertion sort from the previous hypothesis's order.
  auto& order = ws.order;
  for (std::size_t k = 1; k < m; ++k) {
    const int current = order[k];
    const double key = ws.x[static_cast<std::size_t>(current)];
    std::size_t at = k;
    while (at > 0 && ws.x[static_cast<std::size_t>(order[at - 1])] > key) {
      order[at] = order[at - 1];
      --at;
    }
    order[at] = current;
  }
  // Discrete derivatives over gaps narrower than the mean spacing of x' are
  // mostly quantisation and noise (and, where two lights nearly tie in n'·h,
  // unbounded): the gap is floored at the mean spacing (docs/solvers.md: what
  // the floor does on the material sweep).
  const double mean_spacing =
      m > 1 ? (ws.x[static_cast<std::size_t>(order[m - 1])] - ws.x[static_cast<std::size_t>(order[0])]) /
                  static_cast<double>(m - 1)
            : 0.0;
  const double min_gap = std::max(mean_spacing, 1e-12);
  double cost = 0;
  for (std::size_t k = 1; k < m; ++k) {
    const auto a = static_cast<std::size_t>(order[k - 1]), b = static_cast<std::size_t>(order[k]);
    const double dy = ws.y[b] - ws.y[a];
    if (dy >= 0) continue;
    cost += -dy / std::max(ws.x[b] - ws.x[a], min_gap);
  }
  return cost;
}

ElevationEstimate descend_plateau(const ElevationEstimate& start, double azimuth,
                                  const MonotonicOptions& options, MonotonicWorkspace& ws) {
  if (options.plateau_tolerance <= 0) return start;
  const double tolerance = start.cost * (1 + options.plateau_tolerance);
  const double fine = rad_from_deg(options.fine_step_deg);
  ElevationEstimate lowest = start;
  // Whole steps from the start, the last one clamped to θ = 0 (repeated
  // subtraction would drift and stop one step short of the horizon).
  for (int k = 1; lowest.elevation > 0; ++k) {
    const double theta = std::max(0.0, start.elevation - k * fine);
    const double cost = monotonicity_cost(direction_from_elevation_azimuth(theta, azimuth), options, ws);
    if (cost > tolerance) break;
    lowest = {theta, cost};
  }
  return lowest;
}

ElevationEstimate search_elevation(double azimuth, const MonotonicOptions& options, MonotonicWorkspace& ws) {
  ElevationEstimate best{0, std::numeric_limits<double>::infinity()};
  auto try_elevation = [&](double theta) {
    const double cost = monotonicity_cost(direction_from_elevation_azimuth(theta, azimuth), options, ws);
    if (cost < best.cost) best = {theta, cost};
  };
  const double half_pi = kPi / 2;
  const double coarse = rad_from_deg(options.coarse_step_deg);
  const int coarse_steps = static_cast<int>(std::ceil(half_pi / coarse - 1e-9));
  for (int k = 0; k <= coarse_steps; ++k) try_elevation(std::min(k * coarse, half_pi));
  const double centre = best.elevation;
  const double fine = rad_from_deg(options.fine_step_deg);
  const int fine_steps = static_cast<int>(std::ceil(coarse / fine - 1e-9));
  for (int k = -fine_steps; k <= fine_steps; ++k) {
    const double theta = centre + k * fine;
    if (k != 0 && theta >= 0 && theta <= half_pi) try_elevation(theta);
  }
  return descend_plateau(best, azimuth, options, ws);
}

Eigen::Vector3d refine_normal(const Eigen::Vector3d& normal, double step_deg, const MonotonicOptions& options,
                              MonotonicWorkspace& ws) {
  double theta = std::asin(std::clamp(normal.z(), -1.0, 1.0));
  double phi = std::atan2(normal.y(), normal.x());
  double best = monotonicity_cost(normal, options, ws);
  const double fine = rad_from_deg(options.fine_step_deg);
  for (double step = rad_from_deg(step_deg); step >= fine * 0.999; step /= 2) {
    for (bool moved = true; moved;) {
      moved = false;
      // φ moves are scaled by 1/cos θ so both steps are the same angle on the sphere.
      const double phi_step = step / std::max(std::cos(theta), 0.05);
      const double candidates[4][2] = {
          {theta + step, phi}, {theta - step, phi}, {theta, phi + phi_step}, {theta, phi - phi_step}};
      for (const auto& c : candidates) {
        const double t = std::clamp(c[0], 0.0, kPi / 2);
        const double cost = monotonicity_cost(direction_from_elevation_azimuth(t, c[1]), options, ws);
        if (cost < best) {
          best = cost;
          theta = t;
          phi = c[1];
          moved = true;
        }
      }
    }
  }
  // The pattern search climbs the plateau again: descend it at the refined azimuth.
  return direction_from_elevation_azimuth(descend_plateau({theta, best}, phi, options, ws).elevation, phi);
}

RingInterpolation::RingInterpolation(const Eigen::MatrixX3d& lights, const MonotonicOptions& options)
    : samples_(options.ring_samples) {
  const Eigen::Index m = lights.rows();
  std::vector<double> polar;
  for (Eigen::Index j = 0; j < m; ++j) polar.push_back(std::acos(std::clamp(lights(j, 2), -1.0, 1.0)));
  std::sort(polar.begin(), polar.end());
  const auto neighbours = static_cast<std::size_t>(std::min<Eigen::Index>(options.ring_neighbours, m));
  std::vector<std::pair<double, Eigen::Index>> by_angle(static_cast<std::size_t>(m));
  for (const double q : options.ring_quantiles) {
    if (polar.empty()) break;
    const double alpha =
        polar[static_cast<std::size_t>(std::lround(q * static_cast<double>(polar.size() - 1)))];
    // A ring at the viewer carries no azimuth information.
    if (alpha < rad_from_deg(2.0)) continue;
    auto& ring = weights_.emplace_back(static_cast<std::size_t>(samples_));
    for (int k = 0; k < samples_; ++k) {
      const double psi = 2 * kPi * k / samples_;
      const Eigen::Vector3d r(std::sin(alpha) * std::cos(psi), std::sin(alpha) * std::sin(psi),
                              std::cos(alpha));
      for (Eigen::Index j = 0; j < m; ++j) {
        const Eigen::Vector3d l = lights.row(j).transpose();
        by_angle[static_cast<std::size_t>(j)] = {std::atan2(l.cross(r).norm(), l.dot(r)), j};
      }
      std::partial_sort(by_angle.begin(), by_angle.begin() + static_cast<std::ptrdiff_t>(neighbours),
                        by_angle.end());
      double total = 0;
      for (std::size_t t = 0; t < neighbours; ++t) {
        const double w = 1.0 / (by_angle[t].first * by_angle[t].first + 1e-6);
        ring[static_cast<std::size_t>(k)].emplace_back(by_angle[t].second, w);
        total += w;
      }
      for (auto& [j, w] : ring[static_cast<std::size_t>(k)]) w /= total;
    }
  }
}

double RingInterpolation::azimuth(const PixelObservations& pixel) const {
  const int k_count = samples_;
  std::vector<double> cost(static_cast<std::size_t>(k_count), 0.0);
  std::vector<std::vector<double>> rings;
  for (const auto& ring : weights_) {
    auto& values = rings.emplace_back(static_cast<std::size_t>(k_count), 0.0);
    double energy = 0;
    for (int k = 0; k < k_count; ++k) {
      double v = 0;
      for (const auto& [j, w] : ring[static_cast<std::size_t>(k)]) v += w * pixel.values(j);
      values[static_cast<std::size_t>(k)] = v;
      energy += v * v;
    }
    energy = energy / k_count + 1e-30;
    auto at = [&](int index) {
      return values[static_cast<std::size_t>(((index % k_count) + k_count) % k_count)];
    };
    // Axis a (of k_count) at angle a·π/k_count: through sample a/2 (a even) or between two samples (a odd).
    for (int a = 0; a < k_count; ++a) {
      double sum = 0;
      int pairs = 0;
      if (a % 2 == 0) {
        const int c = a / 2;
        for (int d = 1; d < k_count / 2; ++d, ++pairs) sum += std::pow(at(c + d) - at(c - d), 2);
      } else {
        const int c = (a - 1) / 2;
        for (int d = 0; d < k_count / 2; ++d, ++pairs) sum += std::pow(at(c + 1 + d) - at(c - d), 2);
      }
      cost[static_cast<std::size_t>(a)] += sum / pairs / energy;
    }
  }
  const auto best = static_cast<int>(std::min_element(cost.begin(), cost.end()) - cost.begin());
  auto cost_at = [&](int a) { return cost[static_cast<std::size_t>(((a % k_count) + k_count) % k_count)]; };
  const double c0 = cost_at(best), cm = cost_at(best - 1), cp = cost_at(best + 1);
  const double curvature = cm - 2 * c0 + cp;
  const double offset = curvature > 0 ? std::clamp(0.5 * (cm - cp) / curvature, -0.5, 0.5) : 0.0;
  double psi = (best + offset) * kPi / k_count;
  // The axis is a line; the normal leans toward the brighter half of the rings.
  double lean = 0;
  for (const auto& values : rings) {
    for (int k = 0; k < k_count; ++k)
      lean += values[static_cast<std::size_t>(k)] * std::cos(2 * kPi * k / k_count - psi);
  }
  if (lean < 0) psi += kPi;
  return std::remainder(psi, 2 * kPi);
}

double profile_monotonicity(const PixelObservations& pixel, const Eigen::Vector3d& n,
                            double shadow_threshold) {
  std::vector<std::pair<double, double>> profile;
  for (Eigen::Index j = 0; j < pixel.count(); ++j) {
    if (!pixel.usable[static_cast<std::size_t>(j)] || pixel.values(j) <= shadow_threshold) continue;
    const Eigen::Vector3d l = pixel.lights.row(j).transpose();
    const double d = l.dot(n);
    if (d <= 0.05) continue;  // grazing: i/(n·l) is mostly noise
    profile.emplace_back(half_vector(l).dot(n), pixel.values(j) / d);
  }
  if (profile.size() < 2) return 0;
  std::sort(profile.begin(), profile.end());
  std::size_t rising = 0;
  for (std::size_t k = 1; k < profile.size(); ++k)
    rising += profile[k].second >= profile[k - 1].second ? 1 : 0;
  return static_cast<double>(rising) / static_cast<double>(profile.size() - 1);
}

SolveResult solve_monotonic(const Observations& observations, const MonotonicOptions& options,
                            const cv::Mat& azimuth_normals) {
  options.check();
  if (!azimuth_normals.empty() &&
      (azimuth_normals.type() != CV_32FC3 || azimuth_normals.size() != observations.size))
    fail("monotonic: azimuth normals must be a {}x{} CV_32FC3 map", observations.size.width,
         observations.size.height);
  // Distant lights: one ring interpolation for every pixel.
  std::shared_ptr<const RingInterpolation> shared_rings;
  if (!observations.near && observations.lights.rows() > 0)
    shared_rings = std::make_shared<RingInterpolation>(observations.lights, options);
  const detail::DriverSettings settings = detail::driver_settings("monotonic", options);
  SolveResult result;
  detail::run_per_pixel(
      observations, settings,
      [&]() -> detail::PixelCore {
        auto ws = std::make_shared<MonotonicWorkspace>();
        return [ws, &options, &observations, &azimuth_normals, shared_rings](
                   const PixelObservations& pixel, std::size_t p, detail::PixelOutcome& out) {
          int lit = 0;
          for (Eigen::Index j = 0; j < pixel.count(); ++j)
            lit += pixel.usable[static_cast<std::size_t>(j)] && pixel.values(j) > options.shadow_threshold
                       ? 1
                       : 0;
          if (lit < options.min_observations) {
            out.status = detail::PixelOutcome::Status::kTooFewObservations;
            return;
          }
          double phi = 0;
          bool have_phi = false;
          if (!azimuth_normals.empty()) {
            const cv::Vec3f a = azimuth_normals.at<cv::Vec3f>(observations.pixels[p]);
            if (a[0] != 0 || a[1] != 0 || a[2] != 0) {
              phi = std::atan2(static_cast<double>(a[1]), static_cast<double>(a[0]));
              have_phi = true;
            }
          }
          if (!have_phi)
            phi = shared_rings ? shared_rings->azimuth(pixel)
                               : RingInterpolation(pixel.lights, options).azimuth(pixel);
          prepare_monotonic(pixel, *ws);
          const ElevationEstimate e = search_elevation(phi, options, *ws);
          Eigen::Vector3d n = direction_from_elevation_azimuth(e.elevation, phi);
          if (options.refine_step_deg > 0) n = refine_normal(n, options.refine_step_deg, options, *ws);
          std::vector<double> ratios;
          for (Eigen::Index j = 0; j < pixel.count(); ++j) {
            const double d = pixel.lights.row(j).dot(n);
            if (pixel.usable[static_cast<std::size_t>(j)] && pixel.values(j) > options.shadow_threshold &&
                d > 0.1)
              ratios.push_back(pixel.values(j) / d);
          }
          double albedo = 0;
          if (!ratios.empty()) {
            const auto mid = ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2);
            std::nth_element(ratios.begin(), mid, ratios.end());
            albedo = *mid;
          }
          out.status = detail::PixelOutcome::Status::kSolved;
          out.normal = n;
          out.albedo = albedo;
          out.residual = monotonicity_cost(n, options, *ws);
        };
      },
      result);
  result.parameters = options.to_json();
  result.parameters["azimuth"] = azimuth_normals.empty() ? "isotropy" : "normals";
  SolveSummary& s = result.summary;
  const std::string azimuth = azimuth_normals.empty() ? "isotropy" : "normals";
  s.settings = {{"azimuth", azimuth, "azimuth from " + azimuth}};
  s.message = s.format_message();
  return result;
}

}  // namespace lightstage
