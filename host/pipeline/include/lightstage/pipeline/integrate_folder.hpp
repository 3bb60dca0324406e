#pragma once
// Depth and a mesh from a solve folder or a normal map (docs/surfaces.md):
// Poisson or Frankot–Chellappa integration, or fusion with a depth prior,
// written as a surface folder (surface/surface_output.hpp).

#include "lightstage/host/surface/fusion.hpp"
#include "lightstage/host/surface/integration.hpp"

#include <nlohmann/json.hpp>

#include <string>

namespace lightstage::pipeline {

struct IntegrateSettings {
  std::string input;               // a solve folder (normals and, for the mesh colours, its albedo)
  std::string normals;             // or a normal map (16-bit PNG, project encoding); overrides input's
  std::string mask;                // object mask; empty = where the normal map has normals
  std::string albedo;              // albedo image for the mesh colours (PNG or PFM); overrides input's
  std::string out;                 // the surface folder
  std::string prior;               // depth prior to fuse with; empty = integrate
  std::string intrinsics;          // K.txt: perspective camera; empty = orthographic
  std::string method = "poisson";  // poisson, frankot-chellappa (fc)
  std::string mesh = "ply";        // ply, obj, both or none
  // One mesh vertex every N pixels each way; "auto": 1, or as few as keep the
  // mesh near kMeshMaxVertices (a 24 Mpx surface meshed whole is too big to view).
  std::string mesh_step = "auto";
  double pixel_mm = 1.0;         // orthographic pixel size at the object
  double mean_depth = 1.0;       // perspective without a prior: the result's mean depth
  double prior_png_scale = 1.0;  // depth unit per DN of a 16-bit PNG prior
  surface::IntegrationOptions integration;
  surface::FusionOptions fusion;
};

inline constexpr std::size_t kMeshMaxVertices = 4'000'000;

struct IntegrateReport {
  nlohmann::json summary;  // as written to surface.json
  surface::SurfaceStats stats;
};

// Throws InputError naming the file or flag at fault.
IntegrateReport integrate_folder(const IntegrateSettings& settings,
                                 const surface::SurfaceProgress& on_progress = {});

}  // namespace lightstage::pipeline
