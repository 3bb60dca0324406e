#pragma once
// What a camera recorded about a shot, from the file's EXIF (through exiv2):
// JPEG, TIFF and the RAW formats exiv2 reads (DNG, CR2, CR3, NEF, ARW, ...).
// An import puts it into the stack's manifest (docs/stack-format.md).

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace lightstage::io {

struct ExifInfo {
  std::string make, model;
  std::optional<double> exposure_s;  // ExposureTime
  std::optional<double> iso;         // ISOSpeedRatings
  std::optional<double> f_number;    // FNumber
  // DateTimeOriginal (and SubSecTimeOriginal) as "YYYY-MM-DDTHH:MM:SS[.fff]":
  // the camera's clock, which EXIF records without a time zone.
  std::optional<std::string> taken;
  // Orientation, 1 to 8: how the stored pixels turn upright (1: as stored).
  // Not in to_json: the frames a stack keeps are already turned.
  std::optional<int> orientation;

  bool empty() const;
  // The fields present, as {"make", "model", "exposure_s", "iso", "f_number", "taken"}.
  nlohmann::json to_json() const;
};

// `taken` as nanoseconds since 1970 (read as UTC: EXIF has no zone) and the
// step it was written in (1 s, or finer with sub-seconds); nullopt without it.
struct ExifTime {
  std::int64_t ns = 0;
  std::int64_t resolution_ns = 0;
};
std::optional<ExifTime> taken_time(const ExifInfo& exif);

// `image` as the EXIF `orientation` says it is seen (the transforms of EXIF
// 2.3's Orientation tag: mirrored, turned by 180 degrees, or transposed and
// turned by 90); unknown values leave it as stored.
cv::Mat turn_upright(const cv::Mat& image, int orientation);

// Reads the EXIF of `path`. Fields the file does not hold (or holds malformed:
// a zero denominator, an unparsable date) stay empty. Throws InputError naming
// the file when it is missing or exiv2 cannot read it.
ExifInfo read_exif(const std::filesystem::path& path);

}  // namespace lightstage::io
