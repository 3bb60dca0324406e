#pragma once
// The project's normal-map encoding (ARCHITECTURE.md): a 16-bit RGB PNG with
// value = round((n + 1) / 2 · 65535) per component, the red channel holding x,
// green y, blue z (camera frame: x right, y up, z toward the camera), and all
// three channels 0 where there is no normal. In memory, normals are CV_32FC3
// with channels in (x, y, z) order — not BGR; the BGR swap happens only here.

#include <opencv2/core.hpp>

#include <filesystem>
#include <string>

namespace lightstage::io {

struct DecodedNormals {
  cv::Mat normals;  // CV_32FC3 (x, y, z), unit length where valid, zero elsewhere
  cv::Mat valid;    // CV_8UC1, 255 where the file holds a normal
};

// Encodes unit normals (CV_32FC3, x y z) as the CV_16UC3 BGR image that
// cv::imwrite turns into the file. Pixels outside `mask` (CV_8UC1, nonzero =
// inside; empty = everywhere) and pixels whose normal is zero or not finite
// are written as 0. Normals are renormalised before encoding.
cv::Mat encode_normal_map(const cv::Mat& normals, const cv::Mat& mask = {});

// Decodes an encoded image (CV_16UC3, or CV_8UC3 scaled by 255, BGR as read).
// A pixel whose three channels are all 0 is invalid. `source` names the image
// in error messages.
DecodedNormals decode_normal_map(const cv::Mat& encoded, const std::string& source);

// encode_normal_map + an atomic 16-bit PNG write.
void write_normal_map(const std::filesystem::path& path, const cv::Mat& normals, const cv::Mat& mask = {});

// Reads and decodes a normal-map PNG; throws InputError naming the file.
DecodedNormals read_normal_map(const std::filesystem::path& path);

// The usual 8-bit picture of a normal map: colour = round((n + 1) / 2 · 255),
// red = x; black outside the mask. Returns CV_8UC3 (BGR).
cv::Mat normal_visualisation(const cv::Mat& normals, const cv::Mat& mask = {});

// normal_visualisation + an atomic 8-bit PNG write.
void write_normal_visualisation(const std::filesystem::path& path, const cv::Mat& normals,
                                const cv::Mat& mask = {});

}  // namespace lightstage::io
