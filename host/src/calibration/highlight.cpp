#include "lightstage/host/calibration/highlight.hpp"

#include "lightstage/common/error.hpp"

#include <Eigen/Dense>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

namespace lightstage::calibration {
namespace {

// Blobs this small are about the lens blur's size: a thresholded centroid
// would be pulled toward pixel centres ("pixel locking"), so their centre
// comes from a fitted blur spot instead.
constexpr int kSmallBlobPixels = 40;
constexpr int kFitHalfWindow = 3;  // 7 × 7 pixels

double pixel_integral(double lo, double hi, double centre, double sigma) {
  const double k = 1 / (sigma * std::sqrt(2.0));
  return 0.5 * (std::erf((hi - centre) * k) - std::erf((lo - centre) * k));
}

struct Spot {
  Vec2 centre;
  Eigen::Matrix2d covariance;  // of the centre, px²
};

// Least-squares fit of a pixel-integrated Gaussian spot a·G(u, v, σ) + b to
// `diff` around `start` (image points); nullopt when it does not converge to
// a plausible spot. The centre's covariance is σ̂² (JᵀJ)⁻¹ with σ̂² the
// window's residual variance; the spot's own shot noise makes the pixels that
// place it noisier than that average, so it runs 20–40% low for faint spots
// on a bright background.
std::optional<Spot> fit_spot(const cv::Mat& diff, const cv::Point& roi_origin, const Vec2& start,
                             double peak) {
  const int cc = static_cast<int>(std::floor(start.x())) - roi_origin.x;
  const int cr = static_cast<int>(std::floor(start.y())) - roi_origin.y;
  if (cc - kFitHalfWindow < 0 || cr - kFitHalfWindow < 0 || cc + kFitHalfWindow >= diff.cols ||
      cr + kFitHalfWindow >= diff.rows)
    return std::nullopt;
  struct Sample {
    double x, y, value;
  };
  std::vector<Sample> samples;
  for (int r = cr - kFitHalfWindow; r <= cr + kFitHalfWindow; ++r)
    for (int c = cc - kFitHalfWindow; c <= cc + kFitHalfWindow; ++c)
      samples.push_back({static_cast<double>(roi_origin.x + c), static_cast<double>(roi_origin.y + r),
                         static_cast<double>(diff.at<float>(r, c))});
  using Params = Eigen::Matrix<double, 5, 1>;  // amplitude (energy), u, v, sigma, background
  Params p;
  p << peak * 2 * kPi * 0.64, start.x(), start.y(), 0.8, 0.0;
  auto model = [](const Params& q, const Sample& s) {
    return q(0) * pixel_integral(s.x, s.x + 1, q(1), q(3)) * pixel_integral(s.y, s.y + 1, q(2), q(3)) + q(4);
  };
  auto cost = [&](const Params& q) {
    double sum = 0;
    for (const auto& s : samples) sum += std::pow(model(q, s) - s.value, 2);
    return sum;
  };
  // JᵀJ and Jᵀr at q (central differences).
  auto normal_equations = [&](const Params& q, Eigen::Matrix<double, 5, 5>* jtj, Params* jtr) {
    jtj->setZero();
    jtr->setZero();
    for (const auto& s : samples) {
      Params j;
      for (int k = 0; k < 5; ++k) {
        const double h = 1e-6 * std::max(1.0, std::abs(q(k)));
        Params plus = q, minus = q;
        plus(k) += h;
        minus(k) -= h;
        j(k) = (model(plus, s) - model(minus, s)) / (2 * h);
      }
      *jtj += j * j.transpose();
      *jtr += j * (model(q, s) - s.value);
    }
  };
  double lambda = 1e-3, current = cost(p);
  Eigen::Matrix<double, 5, 5> jtj;
  Params jtr;
  for (int iteration = 0; iteration < 50; ++iteration) {
    normal_equations(p, &jtj, &jtr);
    Eigen::Matrix<double, 5, 5> damped = jtj;
    damped.diagonal() *= 1 + lambda;
    const Params step = damped.ldlt().solve(-jtr);
    if (!step.allFinite()) return std::nullopt;
    const Params next = p + step;
    const double next_cost = next(3) > 0.05 ? cost(next) : current * 2;
    if (next_cost < current) {
      p = next;
      current = next_cost;
      lambda *= 0.3;
      if (step.segment<2>(1).norm() < 1e-7) break;
    } else {
      lambda *= 10;
      if (lambda > 1e8) break;
    }
  }
  const Vec2 centre(p(1), p(2));
  if (!(p(0) > 0) || !(p(3) > 0.2 && p(3) < 4) || (centre - start).norm() > 1.5) return std::nullopt;
  normal_equations(p, &jtj, &jtr);
  const Eigen::Matrix<double, 5, 5> inverse = jtj.inverse();
  const double variance = current / static_cast<double>(samples.size() - 5);
  Spot spot{centre, variance * inverse.block<2, 2>(1, 1)};
  if (!spot.covariance.allFinite() || !(spot.covariance.determinant() > 0)) return std::nullopt;
  return spot;
}

}  // namespace

void HighlightOptions::check() const {
  if (!(min_peak > 0 && min_peak < 1)) fail("HighlightOptions.min_peak: must be in (0, 1), got {}", min_peak);
  if (!(threshold_fraction > 0 && threshold_fraction < 1))
    fail("HighlightOptions.threshold_fraction: must be in (0, 1), got {}", threshold_fraction);
  if (!(second_blob_ratio > 0 && second_blob_ratio <= 1))
    fail("HighlightOptions.second_blob_ratio: must be in (0, 1], got {}", second_blob_ratio);
  if (!(max_saturated_fraction > 0 && max_saturated_fraction <= 1))
    fail("HighlightOptions.max_saturated_fraction: must be in (0, 1], got {}", max_saturated_fraction);
  if (!(limb_margin_px >= 0))
    fail("HighlightOptions.limb_margin_px: must not be negative, got {}", limb_margin_px);
}

const char* status_name(HighlightStatus status) {
  switch (status) {
    case HighlightStatus::kFound:
      return "found";
    case HighlightStatus::kMissing:
      return "missing";
    case HighlightStatus::kOverexposed:
      return "overexposed";
    case HighlightStatus::kAmbiguous:
      return "ambiguous";
  }
  return "?";
}

nlohmann::json Highlight::to_json() const {
  nlohmann::json j{{"status", status_name(status)},
                   {"peak", peak},
                   {"pixels", pixels},
                   {"saturated_pixels", saturated_pixels},
                   {"second_blob_ratio", second_blob_ratio}};
  if (status == HighlightStatus::kFound || status == HighlightStatus::kAmbiguous) {
    j["centre_px"] = {centre_px.x(), centre_px.y()};
    j["covariance_px2"] = {covariance_px(0, 0), covariance_px(0, 1), covariance_px(1, 1)};
  }
  if (!note.empty()) j["note"] = note;
  return j;
}

cv::Rect highlight_region(const ImageCircle& circle, cv::Size size) {
  const int x0 = static_cast<int>(std::floor(circle.centre_px.x() - circle.radius_px)) - 1;
  const int y0 = static_cast<int>(std::floor(circle.centre_px.y() - circle.radius_px)) - 1;
  const int side = static_cast<int>(std::ceil(2 * circle.radius_px)) + 3;
  return cv::Rect(x0, y0, side, side) & cv::Rect(cv::Point(0, 0), size);
}

Highlight find_highlight(const cv::Mat& grey, const cv::Mat& background, const cv::Mat& saturated,
                         const ImageCircle& circle, const HighlightOptions& options) {
  Highlight result;
  const cv::Rect roi = highlight_region(circle, grey.size());
  if (roi.empty()) {
    result.note = "the sphere lies outside the image";
    return result;
  }
  // Background-subtracted values inside the outline; noise from their spread.
  cv::Mat diff(roi.size(), CV_32FC1, cv::Scalar::all(0));
  cv::Mat inside(roi.size(), CV_8UC1, cv::Scalar::all(0));
  std::vector<float> samples;
  int sphere_pixels = 0, clipped = 0;
  for (int r = 0; r < roi.height; ++r) {
    for (int c = 0; c < roi.width; ++c) {
      const int row = roi.y + r, col = roi.x + c;
      if ((Vec2(col + 0.5, row + 0.5) - circle.centre_px).norm() > circle.radius_px) continue;
      inside.at<std::uint8_t>(r, c) = 255;
      const float d = grey.at<float>(row, col) - background.at<float>(row, col);
      diff.at<float>(r, c) = d;
      samples.push_back(d);
      ++sphere_pixels;
      if (saturated.at<std::uint8_t>(row, col) != 0) ++clipped;
    }
  }
  if (sphere_pixels == 0) {
    result.note = "the sphere covers no pixel";
    return result;
  }
  if (clipped > options.max_saturated_fraction * sphere_pixels) {
    result.status = HighlightStatus::kOverexposed;
    result.note =
        fmt::format("{} of the sphere's {} pixels are saturated ({:.1f}%, more than {:.1f}%)", clipped,
                    sphere_pixels, 100.0 * clipped / sphere_pixels, 100 * options.max_saturated_fraction);
    return result;
  }
  // The surroundings a sphere mirrors are lit by this frame's LED, so they may be
  // brighter or darker than in the median image: remove the frame's own offset.
  std::vector<float> offsets;
  for (int r = 0; r < roi.height; ++r)
    for (int c = 0; c < roi.width; ++c)
      if (inside.at<std::uint8_t>(r, c) != 0) offsets.push_back(diff.at<float>(r, c));
  const auto centre = offsets.begin() + static_cast<std::ptrdiff_t>(offsets.size() / 2);
  std::nth_element(offsets.begin(), centre, offsets.end());
  const float offset = *centre;
  diff -= offset;
  diff.setTo(0, inside == 0);
  for (auto& s : samples) s = std::abs(s - offset);
  const auto middle = samples.begin() + static_cast<std::ptrdiff_t>(samples.size() / 2);
  std::nth_element(samples.begin(), middle, samples.end());
  const double noise = 1.4826 * *middle;
  double peak = 0;
  cv::Point peak_at;
  cv::minMaxLoc(diff, nullptr, &peak, nullptr, &peak_at, inside);
  result.peak = peak;
  if (peak < options.min_peak) {
    result.note = fmt::format("no highlight: the brightest point is {:.4f} above the median image (needs {})",
                              peak, options.min_peak);
    return result;
  }
  const double threshold = std::max(options.threshold_fraction * peak, 5 * noise);
  cv::Mat blobs;
  cv::compare(diff, threshold, blobs, cv::CMP_GT);
  blobs &= inside;
  cv::Mat labels;
  const int count = cv::connectedComponents(blobs, labels, 8, CV_32S);
  struct Blob {
    double energy = 0, su = 0, sv = 0;
    double pu = 0, pv = 0, suu = 0, suv = 0, svv = 0;  // unweighted sums of u, v, u², uv, v²
    int pixels = 0, saturated = 0;
    double cu = 0, cv = 0;    // centroid of saturated pixels (sums)
    double cuu = 0, cvv = 0;  // their second moments
  };
  std::vector<Blob> found(static_cast<std::size_t>(count));
  for (int r = 0; r < roi.height; ++r) {
    for (int c = 0; c < roi.width; ++c) {
      const int label = labels.at<int>(r, c);
      if (label == 0) continue;
      Blob& b = found[static_cast<std::size_t>(label)];
      const double w = diff.at<float>(r, c);
      const double u = roi.x + c + 0.5, v = roi.y + r + 0.5;
      b.energy += w;
      b.su += w * u;
      b.sv += w * v;
      b.pu += u;
      b.pv += v;
      b.suu += u * u;
      b.suv += u * v;
      b.svv += v * v;
      ++b.pixels;
      if (saturated.at<std::uint8_t>(roi.y + r, roi.x + c) != 0) {
        ++b.saturated;
        b.cu += u;
        b.cv += v;
        b.cuu += u * u;
        b.cvv += v * v;
      }
    }
  }
  std::vector<std::size_t> order;
  for (std::size_t i = 1; i < found.size(); ++i) order.push_back(i);
  // Saturated blobs first (the LED itself is the brightest thing), then by energy.
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if ((found[a].saturated > 0) != (found[b].saturated > 0)) return found[a].saturated > 0;
    return found[a].energy > found[b].energy;
  });
  if (order.empty()) {
    result.note = "no highlight above the noise";
    return result;
  }
  const Blob& main = found[order.front()];
  result.pixels = main.pixels;
  result.saturated_pixels = main.saturated;
  if (main.saturated > 0) {
    // The saturated core's centroid: its error comes from the pixels along the
    // core's edge (2πr of them) that are in or out by chance, each moving it
    // by its offset over the core's n pixels: per axis Σ (u − ū)² · 1/12 / n²
    // with Σ (u − ū)² ≈ 2πr · r²/2 along the edge.
    const double n = main.saturated;
    result.centre_px = Vec2(main.cu / n, main.cv / n);
    const double spread = (main.cuu + main.cvv) / n - result.centre_px.squaredNorm();  // ≈ r²/2 for a disk
    const double radius = std::sqrt(std::max(2 * spread, 0.25));
    const double variance = (2 * kPi * radius) * (radius * radius / 2) / 12 / (n * n);
    result.covariance_px = Eigen::Matrix2d::Identity() * variance;
  } else {
    // The intensity-weighted centroid: Var(ū) = σ² Σ (u − ū)² / E² per pixel
    // of noise σ, with a floor of one pixel's quantisation shared by the blob.
    result.centre_px = Vec2(main.su / main.energy, main.sv / main.energy);
    const Vec2 c = result.centre_px;
    const double n = main.pixels;
    const double uu = main.suu - 2 * c.x() * main.pu + n * c.x() * c.x();
    const double vv = main.svv - 2 * c.y() * main.pv + n * c.y() * c.y();
    const double uv = main.suv - c.x() * main.pv - c.y() * main.pu + n * c.x() * c.y();
    Eigen::Matrix2d scatter;
    scatter << uu, uv, uv, vv;
    result.covariance_px = (noise * noise / (main.energy * main.energy)) * scatter +
                           Eigen::Matrix2d::Identity() * (1.0 / 12.0) / (n * n);
  }
  if (main.saturated == 0 && main.pixels <= kSmallBlobPixels) {
    if (const auto spot = fit_spot(diff, roi.tl(), result.centre_px, peak)) {
      result.centre_px = spot->centre;
      result.covariance_px = spot->covariance;
    }
  }
  if (order.size() > 1) result.second_blob_ratio = found[order[1]].energy / main.energy;
  const double from_limb = circle.radius_px - (result.centre_px - circle.centre_px).norm();
  if (from_limb < options.limb_margin_px) {
    result.status = HighlightStatus::kMissing;
    result.note = fmt::format(
        "the highlight sits on the sphere's outline ({:.1f} px inside), too grazing to use", from_limb);
    return result;
  }
  if (result.second_blob_ratio >= options.second_blob_ratio) {
    const Blob& second = found[order[1]];
    result.status = HighlightStatus::kAmbiguous;
    result.note = fmt::format(
        "two reflections: the strongest at ({:.1f}, {:.1f}), another at ({:.1f}, {:.1f}) with {:.0f}% of its "
        "energy",
        result.centre_px.x(), result.centre_px.y(), second.su / second.energy, second.sv / second.energy,
        100 * result.second_blob_ratio);
    return result;
  }
  result.status = HighlightStatus::kFound;
  return result;
}

}  // namespace lightstage::calibration
