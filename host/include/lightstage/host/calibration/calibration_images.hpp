#pragma once
// The images of a calibration stack (a chrome sphere, a matte sphere or a
// white target under each light), read from any stack folder: only
// filenames.txt and the images are needed — no light files, no mask — so
// simulated stacks, captures and public datasets all work. When present,
// manifest.json adds LED ids, black and saturation levels and the camera,
// and mask.png the object's outline.

#include "lightstage/host/calibration/camera_geometry.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::calibration {

struct CalibrationImages {
  std::filesystem::path folder;
  std::vector<std::string> filenames;  // as listed in filenames.txt
  std::vector<int> led_ids;            // per image; -1 when unknown
  // Per image, CV_32FC1: (raw − black level) / full scale, colour made grey
  // with BT.601 weights (radiometry.hpp's convention).
  std::vector<cv::Mat> grey;
  // Per image, CV_8UC1: 255 where any channel is at or above the saturation level.
  std::vector<cv::Mat> saturated;
  cv::Mat mask;                          // mask.png as CV_8UC1 (255 inside), empty when absent
  std::optional<CameraGeometry> camera;  // from manifest.json ("camera" or "simulation.camera")

  int width() const { return grey.empty() ? 0 : grey.front().cols; }
  int height() const { return grey.empty() ? 0 : grey.front().rows; }
  std::size_t size() const { return grey.size(); }
};

// Reads `folder`. Throws InputError naming the file (and line or field) when
// filenames.txt is missing or lists fewer than `min_images` images, an image
// is missing or unreadable, images differ in size or type, or the mask or
// manifest does not fit.
CalibrationImages load_calibration_images(const std::filesystem::path& folder, int min_images = 1,
                                          int threads = 0);

// The camera a stack's manifest.json records ("camera", or the simulator's
// "simulation.camera"); nullopt when it records none. Errors name the file and key.
std::optional<CameraGeometry> camera_from_manifest(const std::filesystem::path& manifest);

// Per-pixel median over `images` (CV_32FC1, same size): each light's
// highlight is in one image only, so the median keeps what every image shares
// (the sphere lit by its surroundings, room lights) and drops the highlights.
cv::Mat median_image(const std::vector<cv::Mat>& images);

// Per-pixel maximum over `images`.
cv::Mat max_image(const std::vector<cv::Mat>& images);

}  // namespace lightstage::calibration
