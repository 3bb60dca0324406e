#pragma once
// Pictures of a light calibration, for a person to check at a glance:
// the lights on the hemisphere (a polar plot: azimuth around, elevation from
// 0° at the rim to 90° at the centre), calibrated against the rig's nominal
// layout; and each chrome-sphere view with the fitted outline and every
// detected highlight marked.

#include "lightstage/host/calibration/light_calibration.hpp"

#include <opencv2/core.hpp>

#include <filesystem>

namespace lightstage::calibration {

// CV_8UC3 (BGR) picture, `size` pixels square.
cv::Mat hemisphere_plot(const LightCalibration& calibration, int size = 900);

// `view` (CV_32FC1, e.g. the stack's maximum image) tone-mapped, with the
// spheres seen in `stack` and their highlights drawn; CV_8UC3.
cv::Mat highlight_overlay(const cv::Mat& view, const LightCalibration& calibration,
                          const std::filesystem::path& stack);

}  // namespace lightstage::calibration
