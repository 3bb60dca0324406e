#pragma once
// The specular highlight of one light on a mirror sphere, to sub-pixel
// accuracy. What every image shares (the sphere mirroring its surroundings,
// room lights) is removed by subtracting the stack's median image; what is
// left inside the sphere's outline is grouped into blobs. The strongest blob
// is the highlight. Its centre: when it saturates, the centroid of its
// saturated core (blooming spreads a core but keeps it centred); when it is
// about the size of the lens blur, a fitted pixel-integrated Gaussian spot
// (a thresholded centroid of so few pixels is pulled toward pixel centres);
// otherwise the intensity-weighted centroid. Each centre comes with its
// covariance from the image noise (the fit's, or the centroid's error
// propagation), which weights it when LED positions are fitted. A second blob
// nearly as strong (another reflection) is reported, as are frames without a
// highlight and overexposed frames — never guessed.

#include "lightstage/host/calibration/sphere_detection.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <string>

namespace lightstage::calibration {

struct HighlightOptions {
  // Peak above the median image (fraction of full scale) below which there is no highlight.
  double min_peak = 0.005;
  // Pixels above this fraction of the peak (and above the noise) form the highlight's blob.
  double threshold_fraction = 0.05;
  // A separate blob with at least this fraction of the highlight's energy is a second reflection.
  double second_blob_ratio = 0.25;
  // A frame with more than this fraction of the sphere saturated is overexposed.
  double max_saturated_fraction = 0.02;
  // Highlights closer than this to the outline (in pixels) are unreliable: reported as missing.
  double limb_margin_px = 1.5;

  void check() const;  // throws InputError naming the field
};

enum class HighlightStatus { kFound, kMissing, kOverexposed, kAmbiguous };
const char* status_name(HighlightStatus status);

struct Highlight {
  HighlightStatus status = HighlightStatus::kMissing;
  Vec2 centre_px = Vec2::Zero();  // image point, valid when found (or ambiguous)
  // Covariance of centre_px (px²) from the image noise, valid with centre_px.
  Eigen::Matrix2d covariance_px = Eigen::Matrix2d::Identity();
  double peak = 0;               // above the median image, fraction of full scale
  int pixels = 0;                // in the highlight's blob
  int saturated_pixels = 0;      // in the blob
  double second_blob_ratio = 0;  // energy of the next blob / the highlight's
  std::string note;              // why it is missing / ambiguous / overexposed

  // Ambiguous highlights are used (the strongest blob) but reported.
  bool usable() const { return status == HighlightStatus::kFound || status == HighlightStatus::kAmbiguous; }
  nlohmann::json to_json() const;
};

// The pixels of an image of `size` that find_highlight looks at for `circle`:
// the circle's bounding square with a pixel's margin, cut to the image.
cv::Rect highlight_region(const ImageCircle& circle, cv::Size size);

// Finds the highlight in `grey` (CV_32FC1) inside `circle`, with `background`
// (the median image) subtracted and `saturated` (CV_8UC1) flagging clipped pixels.
Highlight find_highlight(const cv::Mat& grey, const cv::Mat& background, const cv::Mat& saturated,
                         const ImageCircle& circle, const HighlightOptions& options);

}  // namespace lightstage::calibration
