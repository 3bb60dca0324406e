#pragma once
// The simulated DSLR's raw files: one shot as an uncompressed, single-IFD
// Adobe DNG 1.4 holding the colour-filter mosaic exactly as the sensor read it
// (black level included), so that raw readers (LibRaw, exiv2) see what they
// would see from a real camera.
//
// What the file says (IFD 0, little-endian TIFF):
//   - the image: 16 bits per sample, one sample per pixel, no compression,
//     PhotometricInterpretation CFA (32803), Orientation 1;
//   - the CFA: CFARepeatPatternDim 2×2, CFAPattern from `cfa` (R = 0, G = 1,
//     B = 2), CFAPlaneColor {R, G, B}, CFALayout 1 (rectangular);
//   - the levels: BlackLevelRepeatDim 2×2 with one BlackLevel per site of the
//     pattern, WhiteLevel;
//   - the colour: ColorMatrix1 the identity (the simulated sensor's filters are
//     the working space's primaries), CalibrationIlluminant1 D65,
//     AsShotNeutral {1, 1, 1};
//   - the camera: Make, Model, UniqueCameraModel "make model";
//   - an EXIF IFD with ExposureTime, ISOSpeedRatings, FNumber,
//     DateTimeOriginal and SubSecTimeOriginal, each only when known.

#include <opencv2/core.hpp>

#include <array>
#include <chrono>
#include <filesystem>
#include <optional>
#include <string>

namespace lightstage::sim {

struct DngShot {
  // CV_16UC1, even width and height: the colour-filter mosaic as the sensor
  // reads it, in DN (black level included). Any step (an ROI) is fine.
  cv::Mat mosaic;
  // The 2×2 filter pattern, row-major from the top-left pixel: one 'R', two
  // 'G', one 'B' ("RGGB", "BGGR", "GRBG", "GBRG").
  std::array<char, 4> cfa = {'R', 'G', 'G', 'B'};
  // DN per site of the 2×2 pattern, same order as `cfa`; each >= 0 and below
  // white_level. Written as rationals: keep them to whole DN (or simple
  // fractions) for readers that store integers (LibRaw truncates).
  std::array<double, 4> black_level = {0, 0, 0, 0};
  // DN at which the sensor saturates, 1..65535; written rounded to whole DN.
  double white_level = 65535;
  std::string make = "Lightstage";
  std::string model = "Simulated DSLR";
  double exposure_s = 0;  // ExposureTime; 0 = unknown, not written
  double iso = 0;         // ISOSpeedRatings, rounded, at most 65535; 0 = not written
  double f_number = 0;    // FNumber; 0 = not written
  // DateTimeOriginal ("YYYY:MM:DD HH:MM:SS", UTC) and SubSecTimeOriginal
  // (milliseconds, 3 digits); not written when empty.
  std::optional<std::chrono::system_clock::time_point> taken;
};

// Writes `shot` to `path` as described above, atomically: a temporary file in
// the same folder, then a rename over `path`; a reader never sees half a
// file, and on any failure nothing new is left behind.
// Throws lightstage::InputError naming `path` for a mosaic that is not
// CV_16UC1 or has an odd (or zero) width or height; a CFA letter other than
// R/G/B or a pattern without exactly one R, two G and one B; a white level
// outside 1..65535; a black level negative or not below the white level; a
// negative or non-finite exposure, ISO or f-number; and any write error
// (a missing or read-only folder, a full disk).
void write_dng(const std::filesystem::path& path, const DngShot& shot);

}  // namespace lightstage::sim
