#pragma once
// A surface on disk, in one output folder:
//   depth.pfm     float depth (camera.hpp depth values; 0 outside the surface)
//   depth.exr     the same float depth as an EXR (one FLOAT channel named Z, uncompressed)
//   depth.png     16-bit picture of it: DN = 1 + round((d − min)/(max − min) · 65534), 0 outside
//                 (min and max recorded in surface.json)
//   mesh.ply      binary PLY with vertex normals and albedo colours (optional)
//   mesh.obj      OBJ with the same (optional)
//   surface.json  what was computed, how, and the statistics

#include "lightstage/host/surface/camera.hpp"
#include "lightstage/host/surface/integration.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <filesystem>

namespace lightstage::surface {

struct SurfaceFiles {
  bool ply = true;
  bool obj = false;
  int mesh_step = 1;  // MeshOptions::step
};

// Writes the files above into `dir` (created if needed); `normals` (the
// photometric ones, optional: else the surface's own) and `albedo`
// (optional) go into the mesh; `extra` keys are added to
// surface.json. Returns the JSON written.
nlohmann::json write_surface_outputs(const std::filesystem::path& dir, const SurfaceResult& surface,
                                     const CameraModel& camera, const cv::Mat& normals, const cv::Mat& albedo,
                                     const SurfaceFiles& files,
                                     const nlohmann::json& extra = nlohmann::json::object());

}  // namespace lightstage::surface
