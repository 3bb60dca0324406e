#pragma once
// Camera RAW files (DNG, CR2, CR3, NEF, ARW, ...) as linear images, through
// LibRaw. What photometric stereo needs is the sensor's response, so nothing
// of a raw converter's rendering is applied: no white balance, no colour
// matrix, no tone or gamma curve. Each value is
//   (raw − black) / (white − black) · 65535
// with the black level of its own filter site (the file's per-channel and
// pattern black levels) and the file's white level, so that 65535 is exactly
// where the sensor clips: an observation at 65535 is flagged saturated by
// radiometry (its default saturation level for 16-bit images); unsaturated
// values stop at 65534. Values below black read 0.
//
// Demosaicing (docs/stack-format.md, "Camera RAW files"):
// - half (the default): each 2×2 block of a Bayer mosaic becomes one pixel, its
//   red and blue site and the mean of its two green sites. No value is
//   interpolated, so the result is exactly linear in the light, at half the
//   width and height.
// - full: LibRaw's demosaic at full size, with unit white balance multipliers
//   and the camera's raw colour space (still linear, but each value mixes
//   neighbouring sites; a pixel within two sites of a clipped one reads 65535).
//   Mosaics that do not bin (X-Trans, SuperCCD, non-square pixels) are always
//   demosaiced so.
// Monochrome sensors and linear (already demosaiced) DNGs keep their full size.

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <array>
#include <filesystem>
#include <string>

namespace lightstage::io {

enum class RawDemosaic { half, full };

// "half" / "full"; parse_raw_demosaic throws InputError naming `what` for another word.
std::string to_string(RawDemosaic demosaic);
RawDemosaic parse_raw_demosaic(const std::string& word, const std::string& what);

// A file LibRaw is asked to decode: known by its extension (case-insensitive).
bool is_raw_file(const std::filesystem::path& path);

struct RawImage {
  cv::Mat image;         // CV_16UC3 (BGR) or CV_16UC1 (monochrome), as above
  std::string camera;    // make and model as the file names them
  std::string mosaic;    // "RGGB", "BGGR", "GRBG", "GBRG", "X-Trans", "monochrome" or "linear"
  std::string demosaic;  // what was done: "half", "full" or "none" (monochrome, linear)
  std::array<double, 4> black = {0, 0, 0, 0};  // the file's black level per colour: R, G, B, second G
  double white = 0;                            // the file's white level

  // {"camera", "mosaic", "demosaic", "black_level", "white_level"} for a manifest.
  nlohmann::json describe() const;
};

// Decodes `path` as above. Throws InputError naming the file when it is
// missing, not a RAW file LibRaw knows, truncated or corrupt, of a layout this
// reader does not take (floating-point, multi-frame, sRAW), decodes to more
// than kMaxImageSide (stack_io.hpp) on a side, or declares a white level not
// above its black level.
RawImage read_raw(const std::filesystem::path& path, RawDemosaic demosaic = RawDemosaic::half);

// The size read_raw gives, from the file's metadata without decoding the pixels.
cv::Size read_raw_size(const std::filesystem::path& path, RawDemosaic demosaic = RawDemosaic::half);

}  // namespace lightstage::io
