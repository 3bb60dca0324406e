#include "lightstage/host/surface/mesh.hpp"
#include "lightstage/common/error.hpp"

#include <algorithm>
#include <cmath>

namespace lightstage::surface {

void MeshOptions::check() const {
  if (!(max_edge_ratio > 0)) fail("mesh: max_edge_ratio must be positive, got {}", max_edge_ratio);
  if (step < 1) fail("mesh: the grid step must be at least 1, got {}", step);
}

int mesh_step_for(std::size_t valid_pixels, std::size_t max_vertices) {
  if (max_vertices == 0) fail("mesh: the vertex budget must be positive");
  int step = 1;
  // Each step keeps about one pixel in step² (rounding up at the edges).
  while (valid_pixels > max_vertices * static_cast<std::size_t>(step) * static_cast<std::size_t>(step))
    ++step;
  return step;
}

Mesh mesh_from_depth(const cv::Mat& depth, const cv::Mat& valid, const CameraModel& camera,
                     const cv::Mat& normals, const cv::Mat& albedo, const MeshOptions& options) {
  options.check();
  camera.check();
  if (depth.type() != CV_32FC1 || depth.size() != camera.size)
    fail("mesh: depth must be CV_32FC1 of the camera's size {}x{}", camera.size.width, camera.size.height);
  if (!valid.empty() && (valid.type() != CV_8UC1 || valid.size() != depth.size()))
    fail("mesh: the validity mask must be CV_8UC1 of the depth's size");
  if (!normals.empty() && (normals.type() != CV_32FC3 || normals.size() != depth.size()))
    fail("mesh: normals must be CV_32FC3 of the depth's size");
  if (!albedo.empty() &&
      ((albedo.type() != CV_32FC1 && albedo.type() != CV_32FC3 && albedo.type() != CV_8UC3) ||
       albedo.size() != depth.size()))
    fail("mesh: albedo must be CV_32FC1, CV_32FC3 or CV_8UC3 of the depth's size");
  const int step = options.step;
  const int rows = (depth.rows + step - 1) / step, cols = (depth.cols + step - 1) / step;  // the grid
  Mesh mesh;
  cv::Mat index(rows, cols, CV_32SC1, cv::Scalar(-1));
  for (int gr = 0; gr < rows; ++gr) {
    for (int gc = 0; gc < cols; ++gc) {
      const int r = gr * step, c = gc * step;
      const double d = depth.at<float>(r, c);
      if ((!valid.empty() && !valid.at<std::uint8_t>(r, c)) || !std::isfinite(d)) continue;
      if (camera.perspective_model() && !(d > 0)) continue;
      index.at<int>(gr, gc) = static_cast<int>(mesh.vertices.size());
      mesh.vertices.push_back(camera.point(c, r, d).cast<float>());
      if (!normals.empty()) {
        const cv::Vec3f n = normals.at<cv::Vec3f>(r, c);
        mesh.normals.emplace_back(n[0], n[1], n[2]);
      }
      if (!albedo.empty()) {
        const auto byte = [](float v) {
          return static_cast<std::uint8_t>(std::clamp(v, 0.0f, 1.0f) * 255.0f + 0.5f);
        };
        if (albedo.type() == CV_32FC1) {
          const auto v = byte(albedo.at<float>(r, c));
          mesh.colours.push_back({v, v, v});
        } else if (albedo.type() == CV_32FC3) {
          const cv::Vec3f bgr = albedo.at<cv::Vec3f>(r, c);
          mesh.colours.push_back({byte(bgr[2]), byte(bgr[1]), byte(bgr[0])});
        } else {
          const cv::Vec3b bgr = albedo.at<cv::Vec3b>(r, c);
          mesh.colours.push_back({bgr[2], bgr[1], bgr[0]});
        }
      }
    }
  }
  auto footprint = [&](const Eigen::Vector3f& p) {
    return step * (camera.perspective_model() ? -p.z() / std::min(camera.K(0, 0), camera.K(1, 1))
                                              : camera.pixel_size);
  };
  auto add = [&](int a, int b, int c) {
    if (a < 0 || b < 0 || c < 0) return false;
    const auto &pa = mesh.vertices[static_cast<std::size_t>(a)],
               &pb = mesh.vertices[static_cast<std::size_t>(b)],
               &pc = mesh.vertices[static_cast<std::size_t>(c)];
    const double limit = options.max_edge_ratio * footprint(pa);
    if ((pa - pb).norm() > limit || (pb - pc).norm() > limit || (pc - pa).norm() > limit) return false;
    mesh.triangles.push_back({a, b, c});
    return true;
  };
  for (int r = 0; r + 1 < rows; ++r) {
    for (int c = 0; c + 1 < cols; ++c) {
      const int i00 = index.at<int>(r, c), i10 = index.at<int>(r, c + 1);
      const int i01 = index.at<int>(r + 1, c), i11 = index.at<int>(r + 1, c + 1);
      // Counter-clockwise seen from +z: right is +x, down the rows is −y.
      const int valid_count = (i00 >= 0) + (i10 >= 0) + (i01 >= 0) + (i11 >= 0);
      if (valid_count == 4) {
        add(i00, i01, i10);
        add(i10, i01, i11);
      } else if (valid_count == 3) {
        if (i00 < 0) add(i10, i01, i11);
        if (i10 < 0) add(i00, i01, i11);
        if (i01 < 0) add(i00, i11, i10);
        if (i11 < 0) add(i00, i01, i10);
      }
    }
  }
  if (normals.empty()) {
    compute_vertex_normals(mesh);
  } else {
    // Vertices whose pixel has no normal take the surface's own.
    Mesh own = mesh;
    compute_vertex_normals(own);
    for (std::size_t i = 0; i < mesh.normals.size(); ++i)
      if (!mesh.normals[i].allFinite() || mesh.normals[i].norm() < 0.5f) mesh.normals[i] = own.normals[i];
  }
  return mesh;
}

void compute_vertex_normals(Mesh& mesh) {
  std::vector<Eigen::Vector3d> sum(mesh.vertices.size(), Eigen::Vector3d::Zero());
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[static_cast<std::size_t>(t[0])].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[static_cast<std::size_t>(t[1])].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[static_cast<std::size_t>(t[2])].cast<double>();
    const Eigen::Vector3d n = (b - a).cross(c - a);  // length = twice the area: area weighting
    for (const int i : t) sum[static_cast<std::size_t>(i)] += n;
  }
  mesh.normals.resize(mesh.vertices.size());
  for (std::size_t i = 0; i < sum.size(); ++i) {
    const double len = sum[i].norm();
    mesh.normals[i] = len > 0 ? Eigen::Vector3f((sum[i] / len).cast<float>()) : Eigen::Vector3f(0, 0, 1);
  }
}

}  // namespace lightstage::surface
