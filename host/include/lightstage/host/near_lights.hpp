#pragma once
// Near point lights (LEDs at calibrated positions): per pixel, the direction
// from the surface point to each LED and the inverse-square falloff relative
// to the object centre, where light intensities are calibrated.
//   l_ij = (p_j − x_i) / |p_j − x_i|,   gain_ij = (|p_j − c| / |p_j − x_i|)²
// Solvers use l_ij as the light direction and divide observations by gain_ij
// (or, equivalently, scale the light rows by it).

#include <Eigen/Core>
#include <opencv2/core/types.hpp>

#include <cstddef>
#include <functional>
#include <vector>

namespace lightstage {

struct NearLights {
  Eigen::MatrixX3d led_positions_mm;  // images × 3, in the dome frame (camera axes, mm)
  Eigen::MatrixX3d points_mm;         // pixels × 3, the surface point each pixel sees (first guess: a plane)
  Eigen::Vector3d object_centre_mm = Eigen::Vector3d::Zero();  // where intensities are calibrated

  std::size_t image_count() const { return static_cast<std::size_t>(led_positions_mm.rows()); }
};

// Fills `directions` (images × 3, unit rows) and `gains` (images) for one pixel.
void near_light_directions(const NearLights& near, std::size_t pixel, Eigen::MatrixX3d& directions,
                           Eigen::VectorXd& gains);
// |p_j − c|² for every LED: the gains' numerators, the same for every pixel.
Eigen::VectorXd near_light_reference(const NearLights& near);

// The viewing ray through image point (u, v) (pixel (col, row) centred at
// (col + 0.5, row + 0.5)): origin and unit direction, dome frame, mm.
using PixelRay =
    std::function<void(const Eigen::Vector2d& uv, Eigen::Vector3d* origin, Eigen::Vector3d* direction)>;

// Where each pixel's viewing ray meets the plane z = plane_z_mm: the first
// guess for NearLights::points_mm when the surface is not known (pixels × 3).
// `origin` is added to every pixel (a band's place in the image).
Eigen::MatrixX3d points_on_plane(const std::vector<cv::Point>& pixels, const PixelRay& ray, double plane_z_mm,
                                 cv::Point origin = {});

}  // namespace lightstage
