#pragma once
// Reading what a dome operator has on disk: a folder of JPEG / PNG / 16-bit
// TIFF photographs and the .lp file naming them (calibration/lp_file.hpp),
// turned into linear frames of a stack (docs/rti-formats.md, "import").

#include "lightstage/host/capture/response_curve.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::io {

// The file an .lp line names, as a name inside the image folder: its last
// path component (RTIBuilder writes absolute Windows paths). Throws
// InputError "source: image name: ..." for an empty name, "." or "..", or
// control characters.
std::string rti_image_name(const std::string& lp_filename, const std::string& source);

// One photograph as a linear 16-bit frame (CV_16UC1 / CV_16UC3, BGR):
// 8-bit data through `response` when given, else the sRGB transfer curve;
// 16-bit data is taken as linear already. Throws InputError naming `source`
// for other depths.
cv::Mat linear_frame(const cv::Mat& image, const std::optional<InverseResponse>& response,
                     const std::string& source);

// The sRGB decoding curve (IEC 61966-2-1): encoded value in [0, 1] -> linear.
double srgb_to_linear(double encoded);

}  // namespace lightstage::io
