#pragma once
// The images of a calibration stack (a chrome sphere, a matte sphere or a
// white target under each light), read from any stack folder: only
// filenames.txt and the images are needed — no light files, no mask — so
// simulated stacks, captures and public datasets all work. When present,
// manifest.json adds LED ids, black and saturation levels and the camera,
// and mask.png the object's outline.

#include "lightstage/common/image_stack.hpp"
#include "lightstage/host/calibration/camera_geometry.hpp"

#include <opencv2/core.hpp>

#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::io {
class RowReader;
}

namespace lightstage::calibration {

struct CalibrationImages {
  std::filesystem::path folder;
  std::vector<std::string> filenames;  // as listed in filenames.txt
  std::vector<int> led_ids;            // per image; -1 when unknown
  std::vector<Frame> frames;           // per image: its file and levels (manifest.json), no pixels
  cv::Size image_size;                 // of every image (the first one's header)
  int image_type = 0;                  // OpenCV type of every image as decoded
  // The part of every image `grey` and `saturated` hold (the whole image unless loaded with a region).
  cv::Rect region;
  // Per image, CV_32FC1: (raw − black level) / full scale, colour made grey
  // with BT.601 weights (radiometry.hpp's convention). Empty in an index.
  std::vector<cv::Mat> grey;
  // Per image, CV_8UC1: 255 where any channel is at or above the saturation level.
  std::vector<cv::Mat> saturated;
  cv::Mat mask;                          // mask.png as CV_8UC1 (255 inside), empty when absent
  std::optional<CameraGeometry> camera;  // from manifest.json ("camera" or "simulation.camera")

  int width() const { return image_size.width; }
  int height() const { return image_size.height; }
  std::size_t size() const { return filenames.size(); }
};

// Reads `folder` without decoding its images: names, manifest, mask, camera,
// and the first image's header. Throws InputError naming the file (and line or
// field) when filenames.txt is missing or lists fewer than `min_images`
// images, the first image is missing or unreadable, or the mask or manifest
// does not fit.
CalibrationImages load_calibration_index(const std::filesystem::path& folder, int min_images = 1);

// Decodes `region` of each image of an index in turn (each frame read only
// down to the region's last row, several at once on `threads`) and gives it to
// `visit` with its index, grey and saturated as below; nothing is kept.
// Throws InputError naming the file for an image of another size or type than
// the first or that fails to decode, and for a region outside the images.
using CalibrationImageVisit =
    std::function<void(std::size_t image, const cv::Mat& grey, const cv::Mat& saturated)>;
void for_each_calibration_image(const CalibrationImages& index, const cv::Rect& region, int threads,
                                const CalibrationImageVisit& visit);

// Decodes `region` of every image of an index into its grey and saturated
// (for_each_calibration_image, kept).
void load_calibration_pixels(CalibrationImages& images, const cv::Rect& region, int threads = 0);

// The index and every image whole.
CalibrationImages load_calibration_images(const std::filesystem::path& folder, int min_images = 1,
                                          int threads = 0);

// Every image of an index read by rows, all kept open from one band to the
// next (io/row_reader.hpp): bands read top to bottom decode each file once, and
// a pass that starts again at the top decodes it again (a camera RAW file is
// decoded whole once, as it opens, and read back from its temporary file).
class CalibrationRows {
 public:
  // Opens every image, several at once on `threads`. Throws InputError naming
  // the file for an image of another size or type than the first.
  explicit CalibrationRows(const CalibrationImages& index, int threads = 0);
  ~CalibrationRows();
  CalibrationRows(const CalibrationRows&) = delete;
  CalibrationRows& operator=(const CalibrationRows&) = delete;

  // Rows [y0, y0 + rows) and `columns` of every image, grey and saturated as
  // CalibrationImages holds them.
  void read(int y0, int rows, const cv::Range& columns, std::vector<cv::Mat>& grey,
            std::vector<cv::Mat>& saturated);
  // Bytes a band holds per pixel of its rows: each image decoded (at most
  // float RGB) and made grey with its saturation flag.
  std::size_t bytes_per_pixel() const;

 private:
  const CalibrationImages& index_;
  int threads_;
  std::vector<std::unique_ptr<io::RowReader>> readers_;
};

// What every image of a stack shows together, per pixel (CV_32FC1, grey as
// above): the median and the maximum, as median_image and max_image give
// them, computed a band of rows at a time (about `band_bytes` of decoded
// images at once) so that no image is held whole.
struct CalibrationViews {
  cv::Mat median, maximum;
};
CalibrationViews calibration_views(const CalibrationImages& index, int threads = 0,
                                   std::size_t band_bytes = std::size_t{64} << 20);

// The camera a stack's manifest.json records ("camera", or the simulator's
// "simulation.camera"); nullopt when it records none. Errors name the file and key.
std::optional<CameraGeometry> camera_from_manifest(const std::filesystem::path& manifest);

// Per-pixel median over `images` (CV_32FC1, same size): each light's
// highlight is in one image only, so the median keeps what every image shares
// (the sphere lit by its surroundings, room lights) and drops the highlights.
cv::Mat median_image(const std::vector<cv::Mat>& images, int threads = 0);

// Per-pixel maximum over `images`.
cv::Mat max_image(const std::vector<cv::Mat>& images);

}  // namespace lightstage::calibration
