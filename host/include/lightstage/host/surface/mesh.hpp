#pragma once
// Triangle meshes from depth maps, and their files: binary PLY (written and
// read; ASCII and big-endian PLY are read too) and Wavefront OBJ (written).
// Vertices are camera-frame points (camera.hpp; mm when the camera's scale is
// known), with per-vertex normals and an albedo colour.

#include "lightstage/host/surface/camera.hpp"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace lightstage::surface {

struct Mesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<Eigen::Vector3f> normals;                // empty or one per vertex
  std::vector<std::array<std::uint8_t, 3>> colours;    // empty or one per vertex (r, g, b)
  std::vector<std::array<std::int32_t, 3>> triangles;  // counter-clockwise seen from the camera
};

// One vertex per valid pixel of a grid of every `step`-th row and column (1:
// every pixel); each 2×2 block of valid grid points gives two triangles (three
// valid points give one), skipping blocks whose depth jumps by more than
// `max_edge_ratio` times the grid's footprint (occluding edges).
// `normals` (CV_32FC3 x y z, optional) become vertex normals, else normals
// are computed from the triangles; `albedo` (CV_32FC1 or CV_32FC3 BGR in
// [0, 1], or CV_8UC3 BGR; optional) becomes the colour.
struct MeshOptions {
  double max_edge_ratio = 20;
  int step = 1;
  void check() const;
};

// The smallest grid step whose share of `valid_pixels` (one in step²) is
// within `max_vertices` (1 when they fit; the grid's rounding at the edges
// may add a row and a column): a 24 Mpx depth map meshed whole is 24 M
// vertices and 48 M triangles, more than mesh viewers handle.
int mesh_step_for(std::size_t valid_pixels, std::size_t max_vertices);
Mesh mesh_from_depth(const cv::Mat& depth, const cv::Mat& valid, const CameraModel& camera,
                     const cv::Mat& normals = {}, const cv::Mat& albedo = {},
                     const MeshOptions& options = {});

// Area-weighted vertex normals from the triangles (replaces mesh.normals).
void compute_vertex_normals(Mesh& mesh);

// Binary little-endian PLY: float x y z, float nx ny nz, uchar red green
// blue (when present), faces as uchar-count int lists. Atomic write.
void write_ply(const std::filesystem::path& path, const Mesh& mesh);
// Wavefront OBJ: "v x y z r g b" (colours in [0, 1], a common extension),
// "vn", and "f a//a b//b c//c". Atomic write.
void write_obj(const std::filesystem::path& path, const Mesh& mesh);

// Reads a PLY (ascii, binary_little_endian or binary_big_endian 1.0): vertex
// x, y, z (any numeric type), optional nx, ny, nz and red, green, blue;
// faces as lists of vertex indices (polygons are fanned into triangles);
// other elements and properties are skipped. Throws InputError naming the
// file and what is wrong.
Mesh read_ply(const std::filesystem::path& path);
// The same from bytes in memory; `source` names them in errors.
Mesh parse_ply(const std::string& bytes, const std::string& source);

}  // namespace lightstage::surface
