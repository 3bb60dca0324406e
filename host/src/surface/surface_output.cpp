#include "lightstage/host/surface/surface_output.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/exr.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/surface/mesh.hpp"
#include "util/atomic_file.hpp"

#include <cmath>

namespace lightstage::surface {

nlohmann::json write_surface_outputs(const std::filesystem::path& dir, const SurfaceResult& surface,
                                     const CameraModel& camera, const cv::Mat& normals, const cv::Mat& albedo,
                                     const SurfaceFiles& files, const nlohmann::json& extra) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) fail("{}: cannot create the output folder: {}", dir.string(), ec.message());
  io::write_pfm(dir / "depth.pfm", surface.depth);
  // Z: the OpenEXR name for depth (and one a depth prior may be read from).
  io::write_exr(dir / "depth.exr", surface.depth, {"Z"});
  double lo = 0, hi = 0;
  const bool any = cv::countNonZero(surface.valid) > 0;
  if (any) cv::minMaxLoc(surface.depth, &lo, &hi, nullptr, nullptr, surface.valid);
  cv::Mat png = cv::Mat::zeros(surface.depth.size(), CV_16UC1);
  const double span = hi > lo ? hi - lo : 1.0;
  for (int r = 0; r < png.rows; ++r)
    for (int c = 0; c < png.cols; ++c)
      if (surface.valid.at<std::uint8_t>(r, c))
        png.at<std::uint16_t>(r, c) =
            static_cast<std::uint16_t>(1 + std::lround((surface.depth.at<float>(r, c) - lo) / span * 65534));
  io::write_png16(dir / "depth.png", png);
  nlohmann::json j = {
      {"depth",
       {{"pfm", "depth.pfm"}, {"exr", "depth.exr"}, {"png", "depth.png"}, {"png_min", lo}, {"png_max", hi}}},
      {"camera", camera.perspective_model()
                     ? nlohmann::json{{"model", "perspective"},
                                      {"K",
                                       {camera.K(0, 0), camera.K(0, 1), camera.K(0, 2), camera.K(1, 0),
                                        camera.K(1, 1), camera.K(1, 2), 0, 0, 1}}}
                     : nlohmann::json{{"model", "orthographic"}, {"pixel_size", camera.pixel_size}}},
      {"stats", surface.stats.to_json()}};
  if (files.ply || files.obj) {
    MeshOptions mesh_options;
    mesh_options.step = files.mesh_step;
    const Mesh mesh = mesh_from_depth(surface.depth, surface.valid, camera, normals, albedo, mesh_options);
    if (files.ply) write_ply(dir / "mesh.ply", mesh);
    if (files.obj) write_obj(dir / "mesh.obj", mesh);
    j["mesh"] = {{"vertices", mesh.vertices.size()},
                 {"triangles", mesh.triangles.size()},
                 {"step", files.mesh_step},
                 {"ply", files.ply ? "mesh.ply" : ""},
                 {"obj", files.obj ? "mesh.obj" : ""}};
  }
  for (const auto& [key, value] : extra.items()) j[key] = value;
  util::write_text_atomic(dir / "surface.json", j.dump(2) + "\n");
  return j;
}

}  // namespace lightstage::surface
