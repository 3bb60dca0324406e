// Meshes and the surface module's file parsers: PLY written and read back,
// OBJ, depth priors (PNG, PFM, PLY rendered into the camera), intrinsics —
// and errors that name the file and the problem.
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/surface/camera.hpp"
#include "lightstage/host/surface/depth_prior.hpp"
#include "lightstage/host/surface/mesh.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

namespace lightstage::surface {
namespace {

using testing::error_of;

// A hemisphere of radius 20 (pixel size 0.5) seen orthographically.
struct Dome {
  cv::Mat depth, mask, normals, albedo;
  CameraModel camera;
};

Dome hemisphere() {
  Dome d;
  const int n = 96;
  d.camera = CameraModel::orthographic(cv::Size(n, n), 0.5);
  d.depth = cv::Mat::zeros(n, n, CV_32FC1);
  d.mask = cv::Mat::zeros(n, n, CV_8UC1);
  d.normals = cv::Mat::zeros(n, n, CV_32FC3);
  d.albedo = cv::Mat::zeros(n, n, CV_32FC1);
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const Vec3 p = d.camera.point(c, r, 0);
      const double rho2 = p.x() * p.x() + p.y() * p.y();
      if (rho2 >= 0.95 * 0.95 * 400) continue;
      const double z = std::sqrt(400 - rho2);
      d.depth.at<float>(r, c) = static_cast<float>(z);
      d.mask.at<std::uint8_t>(r, c) = 255;
      const Vec3 normal = Vec3(p.x(), p.y(), z) / 20;
      d.normals.at<cv::Vec3f>(r, c) = cv::Vec3f(
          static_cast<float>(normal.x()), static_cast<float>(normal.y()), static_cast<float>(normal.z()));
      d.albedo.at<float>(r, c) = c < n / 2 ? 0.25f : 0.75f;
    }
  }
  return d;
}

// Every step-th row and column: the same surface with a step² share of the
// vertices, each one the full mesh's vertex at its pixel.
TEST(Mesh, AGridStepKeepsEveryStepthPixelsVertexAndTheSurface) {
  const Dome d = hemisphere();
  const Mesh whole = mesh_from_depth(d.depth, d.mask, d.camera, d.normals, d.albedo);
  MeshOptions options;
  options.step = 3;
  const Mesh coarse = mesh_from_depth(d.depth, d.mask, d.camera, d.normals, d.albedo, options);
  int expected = 0;
  for (int r = 0; r < d.mask.rows; r += 3)
    for (int c = 0; c < d.mask.cols; c += 3) expected += d.mask.at<std::uint8_t>(r, c) ? 1 : 0;
  ASSERT_EQ(coarse.vertices.size(), static_cast<std::size_t>(expected));
  EXPECT_GT(coarse.triangles.size(), coarse.vertices.size());  // still closed inside: no edge cut
  EXPECT_EQ(coarse.colours.size(), coarse.vertices.size());
  EXPECT_EQ(coarse.normals.size(), coarse.vertices.size());
  // Each coarse vertex is a vertex of the whole mesh, on the hemisphere of radius 20.
  for (const Eigen::Vector3f& v : coarse.vertices) {
    EXPECT_NEAR(v.norm(), 20.0f, 1e-3f);
    EXPECT_TRUE(std::any_of(whole.vertices.begin(), whole.vertices.end(),
                            [&](const Eigen::Vector3f& w) { return (w - v).norm() < 1e-6f; }));
  }
  // The triangles cover about the same area (less a rim up to two pixels wide, where the hemisphere is
  // steep).
  const auto area = [](const Mesh& m) {
    double sum = 0;
    for (const auto& t : m.triangles) {
      const auto &a = m.vertices[static_cast<std::size_t>(t[0])],
                 &b = m.vertices[static_cast<std::size_t>(t[1])],
                 &c = m.vertices[static_cast<std::size_t>(t[2])];
      sum += 0.5 * static_cast<double>((b - a).cross(c - a).norm());
    }
    return sum;
  };
  EXPECT_LT(area(coarse), area(whole));
  EXPECT_GT(area(coarse) / area(whole), 0.85);
  options.step = 0;
  EXPECT_NE(error_of([&] { mesh_from_depth(d.depth, d.mask, d.camera, {}, {}, options); }).find("step"),
            std::string::npos);
}

TEST(Mesh, TheStepForABudgetIsTheSmallestThatKeepsWithinIt) {
  EXPECT_EQ(mesh_step_for(100, 100), 1);
  EXPECT_EQ(mesh_step_for(101, 100), 2);
  EXPECT_EQ(mesh_step_for(400, 100), 2);
  EXPECT_EQ(mesh_step_for(24'000'000, 4'000'000), 3);  // a 6000x4000 depth map: 2.7 M vertices
  EXPECT_EQ(mesh_step_for(0, 4'000'000), 1);
}

TEST(Mesh, PlyRoundTripKeepsVerticesNormalsColoursAndFaces) {
  const Dome d = hemisphere();
  const Mesh mesh = mesh_from_depth(d.depth, d.mask, d.camera, d.normals, d.albedo);
  EXPECT_EQ(mesh.vertices.size(), static_cast<std::size_t>(cv::countNonZero(d.mask)));
  EXPECT_GT(mesh.triangles.size(), mesh.vertices.size());  // ~2 per vertex inside
  const auto path = testing::scratch_dir() / "dome.ply";
  write_ply(path, mesh);
  const Mesh back = read_ply(path);
  ASSERT_EQ(back.vertices.size(), mesh.vertices.size());
  ASSERT_EQ(back.normals.size(), mesh.vertices.size());
  ASSERT_EQ(back.colours.size(), mesh.vertices.size());
  ASSERT_EQ(back.triangles.size(), mesh.triangles.size());
  Eigen::Vector3f lo = back.vertices[0], hi = back.vertices[0];
  for (std::size_t i = 0; i < back.vertices.size(); ++i) {
    EXPECT_EQ(back.vertices[i], mesh.vertices[i]);
    lo = lo.cwiseMin(back.vertices[i]);
    hi = hi.cwiseMax(back.vertices[i]);
    // Normals point out of the sphere centred at the origin.
    EXPECT_GT(back.normals[i].dot(back.vertices[i].normalized()), 0.999f);
  }
  EXPECT_NEAR(hi.z(), 20.0f, 0.1f);
  EXPECT_NEAR(hi.x(), 19.0f, 0.6f);
  EXPECT_NEAR(lo.x(), -19.0f, 0.6f);
  EXPECT_EQ(back.colours.front()[0], 64);  // albedo 0.25 on the left
  // Every face is counter-clockwise seen from the camera.
  for (const auto& t : back.triangles) {
    const Eigen::Vector3f e1 =
        back.vertices[static_cast<std::size_t>(t[1])] - back.vertices[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3f e2 =
        back.vertices[static_cast<std::size_t>(t[2])] - back.vertices[static_cast<std::size_t>(t[0])];
    EXPECT_GT(e1.cross(e2).z(), 0.0f);
  }
}

TEST(Mesh, ComputedNormalsMatchTheSurface) {
  const Dome d = hemisphere();
  const Mesh mesh = mesh_from_depth(d.depth, d.mask, d.camera);
  double worst = 0;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    if (mesh.vertices[i].z() > 10)
      worst =
          std::max(worst, angle_between_deg(mesh.normals[i].cast<double>(), mesh.vertices[i].cast<double>()));
  EXPECT_LT(worst, 3.0);
}

TEST(Mesh, ObjListsVerticesNormalsAndOneBasedFaces) {
  const Dome d = hemisphere();
  const Mesh mesh = mesh_from_depth(d.depth, d.mask, d.camera, d.normals, d.albedo);
  const auto path = testing::scratch_dir() / "dome.obj";
  write_obj(path, mesh);
  std::ifstream in(path);
  std::string line;
  std::size_t v = 0, vn = 0, f = 0;
  long max_index = 0;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key == "v") {
      double x, y, z, r, g, b;
      ASSERT_TRUE(static_cast<bool>(words >> x >> y >> z >> r >> g >> b)) << line;
      EXPECT_LE(r, 1.0);
      ++v;
    } else if (key == "vn") {
      ++vn;
    } else if (key == "f") {
      for (int k = 0; k < 3; ++k) {
        std::string token;
        words >> token;
        const long index = std::stol(token.substr(0, token.find('/')));
        EXPECT_GE(index, 1);
        max_index = std::max(max_index, index);
      }
      ++f;
    }
  }
  EXPECT_EQ(v, mesh.vertices.size());
  EXPECT_EQ(vn, mesh.vertices.size());
  EXPECT_EQ(f, mesh.triangles.size());
  EXPECT_EQ(max_index, static_cast<long>(mesh.vertices.size()));
}

TEST(DepthPrior, MeshRenderedIntoTheCameraReproducesTheDepth) {
  const Dome d = hemisphere();
  const auto path = testing::scratch_dir() / "prior.ply";
  write_ply(path, mesh_from_depth(d.depth, d.mask, d.camera));
  const DepthMap prior = load_depth_prior(path, d.camera);
  int compared = 0;
  for (int r = 0; r < d.mask.rows; ++r)
    for (int c = 0; c < d.mask.cols; ++c)
      if (prior.valid.at<std::uint8_t>(r, c)) {
        ASSERT_TRUE(d.mask.at<std::uint8_t>(r, c));
        EXPECT_NEAR(prior.depth.at<float>(r, c), d.depth.at<float>(r, c), 1e-3);
        ++compared;
      }
  EXPECT_GT(compared, 0.95 * cv::countNonZero(d.mask));
}

TEST(DepthPrior, PerspectiveMeshRendersDistancesAlongTheAxis) {
  Mat3 K;
  K << 100, 0, 31.5, 0, 100, 31.5, 0, 0, 1;
  const CameraModel camera = CameraModel::perspective(cv::Size(64, 64), K);
  // A plane 500 units away, tilted: d(col) = 500 + 0.5·(col − 31.5) roughly.
  cv::Mat depth(64, 64, CV_32FC1);
  for (int r = 0; r < 64; ++r)
    for (int c = 0; c < 64; ++c) depth.at<float>(r, c) = static_cast<float>(500 + 0.5 * (c - 31.5));
  const auto path = testing::scratch_dir() / "plane.ply";
  write_ply(path, mesh_from_depth(depth, {}, camera));
  const DepthMap prior = load_depth_prior(path, camera);
  for (int r = 1; r < 63; r += 7)
    for (int c = 1; c < 63; c += 7) {
      ASSERT_TRUE(prior.valid.at<std::uint8_t>(r, c));
      EXPECT_NEAR(prior.depth.at<float>(r, c), depth.at<float>(r, c), 1e-2);
    }
}

TEST(DepthPrior, PngAndPfmFilesLoadWithScaleAndHoles) {
  const auto dir = testing::scratch_dir();
  cv::Mat png(8, 8, CV_16UC1, cv::Scalar(1500));
  png.at<std::uint16_t>(2, 3) = 0;
  io::write_png16(dir / "d.png", png);
  const CameraModel camera = CameraModel::orthographic(cv::Size(8, 8), 1.0);
  DepthPriorOptions options;
  options.png_scale = 0.5;
  const DepthMap a = load_depth_prior(dir / "d.png", camera, options);
  EXPECT_FLOAT_EQ(a.depth.at<float>(0, 0), 750.0f);
  EXPECT_EQ(a.valid.at<std::uint8_t>(2, 3), 0);
  EXPECT_EQ(cv::countNonZero(a.valid), 63);
  cv::Mat pfm(8, 8, CV_32FC1, cv::Scalar(2.5));
  pfm.at<float>(1, 1) = std::nanf("");
  io::write_pfm(dir / "d.pfm", pfm);
  const DepthMap b = load_depth_prior(dir / "d.pfm", camera);
  EXPECT_EQ(cv::countNonZero(b.valid), 63);
  EXPECT_FLOAT_EQ(b.depth.at<float>(7, 7), 2.5f);
}

TEST(DepthPrior, ErrorsNameTheFileAndTheProblem) {
  const auto dir = testing::scratch_dir();
  const CameraModel camera = CameraModel::orthographic(cv::Size(8, 8), 1.0);
  io::write_png(dir / "eight.png", cv::Mat(8, 8, CV_8UC1, cv::Scalar(3)));
  EXPECT_NE(error_of([&] {
              load_depth_prior(dir / "eight.png", camera);
            }).find("eight.png: a depth PNG must be 16-bit"),
            std::string::npos);
  io::write_png16(dir / "small.png", cv::Mat(4, 8, CV_16UC1, cv::Scalar(3)));
  EXPECT_NE(
      error_of([&] { load_depth_prior(dir / "small.png", camera); }).find("is 8x4 but the images are 8x8"),
      std::string::npos);
  io::write_png16(dir / "empty.png", cv::Mat(8, 8, CV_16UC1, cv::Scalar(0)));
  EXPECT_NE(error_of([&] { load_depth_prior(dir / "empty.png", camera); }).find("holds no valid depth"),
            std::string::npos);
  EXPECT_NE(
      error_of([&] { load_depth_prior(dir / "x.tif", camera); }).find("unknown depth prior format '.tif'"),
      std::string::npos);
}

TEST(Ply, ReadsAsciiAndBigEndianAndFansPolygons) {
  const std::string ascii =
      "ply\nformat ascii 1.0\ncomment a quad\nelement vertex 4\nproperty double x\nproperty double y\n"
      "property double z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0 255 0 0\n1 0 0 0 255 0\n1 1 0 0 0 255\n0 1 0 9 9 9\n4 0 1 2 3\n";
  const Mesh m = parse_ply(ascii, "quad.ply");
  EXPECT_EQ(m.vertices.size(), 4u);
  EXPECT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.colours[1][1], 255);
  std::string be =
      "ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n";
  for (const float v : {1.0f, 2.0f, -3.0f}) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, 4);
    for (int s = 24; s >= 0; s -= 8) be.push_back(static_cast<char>((bits >> s) & 0xff));
  }
  const Mesh b = parse_ply(be, "be.ply");
  ASSERT_EQ(b.vertices.size(), 1u);
  EXPECT_EQ(b.vertices[0], Eigen::Vector3f(1, 2, -3));
}

TEST(Ply, MalformedFilesGiveErrorsNamingTheFile) {
  EXPECT_NE(error_of([] { parse_ply("PLY\n", "a.ply"); }).find("a.ply: not a PLY file"), std::string::npos);
  EXPECT_NE(error_of([] {
              parse_ply("ply\nformat ascii 1.0\nelement vertex 1\n", "b.ply");
            }).find("no 'end_header'"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              parse_ply(
                  "ply\nformat ascii 1.0\nelement vertex 1000000\nproperty float x\nproperty float y\n"
                  "property float z\nend_header\n1 2 3\n",
                  "c.ply");
            }).find("claims 1000000 items but the file is too short"),
            std::string::npos);
  EXPECT_NE(
      error_of([] {
        parse_ply(
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n3 0 0 7\n",
            "d.ply");
      }).find("face 0 refers to vertex 7 of 1"),
      std::string::npos);
  EXPECT_NE(error_of([] { read_ply("/nonexistent/mesh.ply"); }).find("/nonexistent/mesh.ply: cannot open"),
            std::string::npos);
}

TEST(Intrinsics, ParsesDiligentStyleAndRejectsBadMatrices) {
  const Mat3 K = parse_intrinsics("3772.1 0 305.9\n0 3759.0 255.1\n0 0 1\n", "K.txt");
  EXPECT_DOUBLE_EQ(K(0, 0), 3772.1);
  EXPECT_DOUBLE_EQ(K(1, 2), 255.1);
  EXPECT_NE(error_of([] {
              parse_intrinsics("1 0 0 0 1 0 0 0", "K.txt");
            }).find("K.txt: intrinsics: expected nine numbers"),
            std::string::npos);
  EXPECT_NE(error_of([] { parse_intrinsics("1 0 0 0 1 0 0 0 2", "K.txt"); }).find("last row must be 0 0 1"),
            std::string::npos);
  EXPECT_NE(error_of([] { parse_intrinsics("-1 0 0 0 1 0 0 0 1", "K.txt"); }).find("must be positive"),
            std::string::npos);
  EXPECT_NE(
      error_of([] { parse_intrinsics("1 0 0 0 x 0 0 0 1", "K.txt"); }).find("'x' is not a finite number"),
      std::string::npos);
  EXPECT_NE(error_of([] { read_intrinsics("/nonexistent/K.txt"); }).find("/nonexistent/K.txt: cannot open"),
            std::string::npos);
}

TEST(CameraModel, PointAndProjectAreInverse) {
  Mat3 K;
  K << 3772, 0, 305.875, 0, 3759, 255.125, 0, 0, 1;
  const CameraModel p = CameraModel::perspective(cv::Size(612, 512), K);
  const Vec3 x = p.point(100, 400, 1500);
  EXPECT_NEAR(x.z(), -1500, 1e-9);
  EXPECT_LT(x.y(), 0);  // below the centre row: y up
  double c = 0, r = 0, d = 0;
  ASSERT_TRUE(p.project(x, &c, &r, &d));
  EXPECT_NEAR(c, 100, 1e-9);
  EXPECT_NEAR(r, 400, 1e-9);
  EXPECT_NEAR(d, 1500, 1e-9);
}

}  // namespace
}  // namespace lightstage::surface
