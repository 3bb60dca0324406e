#pragma once
// How pixels and depth values map to 3-D points, for everything in surface/:
// integration, fusion, normals from depth, meshes, depth priors.
//
// Camera frame as everywhere (x right, y up, z toward the camera). Pixel
// (col, row) has its centre at (col, row) — the convention of intrinsics
// matrices such as DiLiGenT's K.txt.
//  - Orthographic: the depth value is the height z toward the camera, in the
//    same unit as pixel_size (mm when the rig gives the pitch, else pixels:
//    pixel_size = 1); the point is ((col − cx)·s, −(row − cy)·s, z) with
//    (cx, cy) the image centre.
//  - Perspective (intrinsics K): the depth value d is the distance along the
//    optical axis (positive, in front of the camera); the point is
//    d · ((col − cx)/fx, −(row − cy)/fy, −1).

#include "lightstage/common/geometry.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <string>

namespace lightstage::surface {

struct CameraModel {
  enum class Kind { kOrthographic, kPerspective };
  Kind kind = Kind::kOrthographic;
  cv::Size size;              // image size
  double pixel_size = 1.0;    // orthographic: size of a pixel at the object
  Mat3 K = Mat3::Identity();  // perspective intrinsics (pixels)

  static CameraModel orthographic(cv::Size size, double pixel_size = 1.0);
  static CameraModel perspective(cv::Size size, const Mat3& K);

  bool perspective_model() const { return kind == Kind::kPerspective; }
  // The 3-D point of pixel (col, row) at depth value `depth`.
  Vec3 point(double col, double row, double depth) const;
  // Projects a camera-frame point; false when it is behind a perspective camera.
  bool project(const Vec3& p, double* col, double* row, double* depth) const;
  // Throws InputError naming the broken field.
  void check() const;
};

// Parses a 3×3 intrinsics matrix: nine numbers (whitespace, commas or
// brackets between them), row-major; fx, fy > 0 and a last row of 0 0 1.
// `source` names the text in errors.
Mat3 parse_intrinsics(const std::string& text, const std::string& source);
// Reads and parses a K.txt file; throws InputError naming the file.
Mat3 read_intrinsics(const std::filesystem::path& path);

}  // namespace lightstage::surface
