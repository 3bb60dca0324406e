// The surface outputs' float depth: depth.exr beside depth.pfm holds the same
// depth map (bit for bit), is named in surface.json, and reads back as a
// depth prior.
#include "lightstage/host/io/exr.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/surface/camera.hpp"
#include "lightstage/host/surface/depth_prior.hpp"
#include "lightstage/host/surface/surface_output.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace lightstage::surface {
namespace {

TEST(SurfaceOutput, DepthExrEqualsTheDepthMap) {
  const CameraModel camera = CameraModel::orthographic(cv::Size(21, 17), 0.5);
  SurfaceResult surface;
  surface.depth = cv::Mat::zeros(camera.size, CV_32FC1);
  surface.valid = cv::Mat::zeros(camera.size, CV_8UC1);
  for (int r = 2; r < 15; ++r)
    for (int c = 3; c < 19; ++c) {
      surface.depth.at<float>(r, c) =
          10.0f + std::sin(0.3f * static_cast<float>(c)) * std::sqrt(static_cast<float>(r));
      surface.valid.at<std::uint8_t>(r, c) = 255;
    }
  const auto dir = testing::scratch_dir() / "surface";
  SurfaceFiles files;
  files.ply = false;
  const nlohmann::json j = write_surface_outputs(dir, surface, camera, cv::Mat(), cv::Mat(), files);
  EXPECT_EQ(j["depth"]["exr"], "depth.exr");
  EXPECT_EQ(j["depth"]["pfm"], "depth.pfm");

  const io::ExrFile exr(dir / "depth.exr");
  ASSERT_EQ(exr.header().channels.size(), 1u);
  EXPECT_EQ(exr.header().channels[0].name, "Z");
  EXPECT_EQ(exr.header().channels[0].type, io::ExrPixelType::kFloat32);
  const cv::Mat depth = exr.read({"Z"});
  ASSERT_EQ(depth.type(), CV_32FC1);
  ASSERT_EQ(depth.size(), camera.size);
  EXPECT_EQ(cv::norm(depth, surface.depth, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(depth, io::read_pfm(dir / "depth.pfm"), cv::NORM_INF), 0.0);

  // As a prior: the same depth where the surface is, no depth outside it.
  const DepthMap prior = load_depth_prior(dir / "depth.exr", camera);
  EXPECT_EQ(cv::norm(prior.depth, surface.depth, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(prior.valid, surface.valid, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace lightstage::surface
