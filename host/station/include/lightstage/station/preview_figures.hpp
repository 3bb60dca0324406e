#pragma once
// What the live view shows of a camera frame: the picture, and the figures an
// operator exposes and focuses by — the histogram with the clipped share, and
// a sharpness number that rises as focus improves.

#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

namespace lightstage::station {

// The frame as an 8-bit PNG (full scale of its type maps to 255; grey or BGR as it is).
std::string encode_preview_png(const cv::Mat& frame);

// {"width", "height", "histogram": 64 counts over [0, full scale], "clipped": share of pixels at full
// scale, "mean": mean share of full scale, "sharpness": variance of the Laplacian of the grey image in
// full-scale units x 1e4 (compare between frames of one scene)}.
nlohmann::json preview_figures(const cv::Mat& frame);

}  // namespace lightstage::station
