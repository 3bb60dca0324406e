// The geometry under light calibration, on exact synthetic inputs: circle
// fits, mirror reflection (orthographic and pinhole), ray triangulation, the
// dome intersection and the rigid fit to a nominal layout.
#include "lightstage/common/error.hpp"
#include "lightstage/host/calibration/led_positions.hpp"
#include "lightstage/host/calibration/mirror_sphere.hpp"
#include "lightstage/host/calibration/sphere_detection.hpp"
#include "lightstage/testing/errors.hpp"

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include <random>

namespace lightstage::calibration {
namespace {

using testing::error_of;

TEST(CalibrationCircle, FitsNoisyPointsToTheTrueCircle) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 0.05);
  std::vector<Vec2> points;
  for (int k = 0; k < 400; ++k) {
    const double a = 2 * kPi * k / 400;
    points.emplace_back(123.4 + 87.6 * std::cos(a) + noise(rng), 98.7 + 87.6 * std::sin(a) + noise(rng));
  }
  const ImageCircle c = fit_circle(points);
  EXPECT_NEAR(c.centre_px.x(), 123.4, 0.02);
  EXPECT_NEAR(c.centre_px.y(), 98.7, 0.02);
  EXPECT_NEAR(c.radius_px, 87.6, 0.02);
  EXPECT_NEAR(c.rms_px, 0.05, 0.01);
}

TEST(CalibrationCircle, RejectsTooFewOrCollinearPoints) {
  EXPECT_NE(error_of([] { fit_circle({{0, 0}, {1, 1}}); }).find("at least 3"), std::string::npos);
  EXPECT_NE(error_of([] {
              fit_circle({{0, 0}, {1, 1}, {2, 2}, {3, 3}});
            }).find("collinear"),
            std::string::npos);
}

// A disk rasterised at pixel centres, as a mask: the midpoint fit recovers it to a small fraction of a pixel.
TEST(CalibrationCircle, MaskOutlineGivesSubpixelCircle) {
  cv::Mat mask(300, 400, CV_8UC1, cv::Scalar::all(0));
  const Vec2 centre(201.3, 148.9);
  const double radius = 101.7;
  for (int r = 0; r < mask.rows; ++r)
    for (int c = 0; c < mask.cols; ++c)
      if ((Vec2(c + 0.5, r + 0.5) - centre).norm() <= radius) mask.at<std::uint8_t>(r, c) = 255;
  const auto circles = circles_from_mask(mask, {}, "test mask");
  ASSERT_EQ(circles.size(), 1u);
  EXPECT_LT((circles[0].centre_px - centre).norm(), 0.05);
  EXPECT_NEAR(circles[0].radius_px, radius, 0.05);
  EXPECT_EQ(circles[0].source, "mask");
}

TEST(CalibrationCircle, MaskWithTwoBlobsWhenOneIsExpectedNamesBoth) {
  cv::Mat mask(100, 200, CV_8UC1, cv::Scalar::all(0));
  cv::circle(mask, {50, 50}, 30, cv::Scalar(255), cv::FILLED);
  cv::circle(mask, {150, 50}, 30, cv::Scalar(255), cv::FILLED);
  const std::string message = error_of([&] { circles_from_mask(mask, {}, "two.png"); });
  EXPECT_NE(message.find("two.png: found 2 spheres"), std::string::npos) << message;
  SphereDetectionOptions two;
  two.expected = 2;
  EXPECT_EQ(circles_from_mask(mask, two, "two.png").size(), 2u);
}

TEST(CalibrationCircle, DetectsABrightDiskToSubpixelAndRefusesABlankImage) {
  // An anti-aliased disk (area coverage per pixel) over a dark, slightly noisy background.
  const Vec2 centre(160.37, 121.82);
  const double radius = 80.45;
  cv::Mat image(256, 320, CV_32FC1, cv::Scalar::all(0));
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(0, 0.001f);
  for (int r = 0; r < image.rows; ++r) {
    for (int c = 0; c < image.cols; ++c) {
      int inside = 0;
      for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i)
          if ((Vec2(c + (i + 0.5) / 8, r + (j + 0.5) / 8) - centre).norm() <= radius) ++inside;
      image.at<float>(r, c) = 0.04f * static_cast<float>(inside) / 64 + noise(rng);
    }
  }
  const auto circles = detect_circles(image, {}, "disk");
  ASSERT_EQ(circles.size(), 1u);
  EXPECT_LT((circles[0].centre_px - centre).norm(), 0.03);
  EXPECT_NEAR(circles[0].radius_px, radius, 0.03);
  const std::string message =
      error_of([] { detect_circles(cv::Mat(64, 64, CV_32FC1, cv::Scalar::all(0)), {}, "blank stack"); });
  EXPECT_NE(message.find("blank stack"), std::string::npos) << message;
}

// The mirror direction at the image of the point where n bisects l and v.
TEST(CalibrationMirror, OrthographicHighlightGivesTheLight) {
  CameraGeometry camera = CameraGeometry::unknown(512, 512);
  camera.pixel_pitch_mm = 0.2;
  camera.metric = true;
  ImageCircle circle;
  circle.centre_px = Vec2(256, 256);
  circle.radius_px = 200;
  const MirrorSphere sphere = locate_sphere(circle, camera, 0, 0);
  EXPECT_NEAR(sphere.radius_mm, 40, 1e-12);
  for (const Vec3& light : {Vec3(0.3, 0.2, 0.9), Vec3(-0.9, 0.1, 0.35), Vec3(0, 0, 1)}) {
    const Vec3 l = light.normalized();
    const Vec3 n = (l + Vec3::UnitZ()).normalized();
    const Vec2 uv(256 + 200 * n.x(), 256 - 200 * n.y());
    const auto reflection = reflect_at(sphere, camera, uv);
    ASSERT_TRUE(reflection);
    EXPECT_LT(angle_between_deg(reflection->direction, l), 1e-9);
    EXPECT_LT((reflection->point_mm - 40 * n).norm(), 1e-9);
  }
  EXPECT_FALSE(reflect_at(sphere, camera, Vec2(10, 10)));
}

TEST(CalibrationMirror, PinholeHighlightUsesItsOwnViewingRay) {
  CameraGeometry camera = CameraGeometry::unknown(640, 480);
  camera.model = CameraModel::kPinhole;
  camera.focal_px = 800;
  camera.position_mm = Vec3(0, 0, 600);
  camera.metric = true;
  // A 25 mm sphere at (30, -20, 10): project its outline (the tangent cone) and locate it again.
  const Vec3 centre(30, -20, 10);
  const double radius = 25;
  auto project = [&](const Vec3& p) {
    const Vec3 q = p - camera.position_mm;
    return Vec2(320 + 800 * q.x() / -q.z(), 240 - 800 * q.y() / -q.z());
  };
  std::vector<Vec2> outline;
  const Vec3 axis = (centre - camera.position_mm).normalized();
  const double distance = (centre - camera.position_mm).norm();
  const Vec3 side = axis.cross(Vec3::UnitX()).normalized(), up = axis.cross(side);
  const double half = std::asin(radius / distance);
  for (int k = 0; k < 720; ++k) {
    const double a = 2 * kPi * k / 720;
    const Vec3 ray = std::cos(half) * axis + std::sin(half) * (std::cos(a) * side + std::sin(a) * up);
    outline.push_back(project(camera.position_mm + ray));
  }
  const ImageCircle circle = fit_circle(outline);
  const MirrorSphere sphere = locate_sphere(circle, camera, 0, radius);
  EXPECT_LT((sphere.centre_mm - centre).norm(), 0.5);
  // A highlight: a point on the sphere, its true reflected direction, through its own viewing ray.
  const Vec3 n = Vec3(0.2, 0.3, 0.93).normalized();
  const Vec3 x = centre + radius * n;
  const Vec3 view = (camera.position_mm - x).normalized();
  const Vec3 light = 2 * n.dot(view) * n - view;
  const auto reflection = reflect_at(sphere, camera, project(x));
  ASSERT_TRUE(reflection);
  // Known limit: an off-axis sphere images as an ellipse whose centre is not the
  // projection of the sphere's centre; the circle fit places the sphere ~0.5 mm
  // off here, which costs ~0.3 degrees (docs/calibration.md).
  EXPECT_LT(angle_between_deg(reflection->direction, light), 0.5);
  // The orthographic formula on the same image point would be far off: perspective matters here.
  const Vec3 ortho_n((project(x).x() - circle.centre_px.x()) / circle.radius_px,
                     (circle.centre_px.y() - project(x).y()) / circle.radius_px, 0);
  const Vec3 ortho_normal(ortho_n.x(), ortho_n.y(), std::sqrt(1 - ortho_n.squaredNorm()));
  const Vec3 ortho_light = 2 * ortho_normal.z() * ortho_normal - Vec3::UnitZ();
  EXPECT_GT(angle_between_deg(ortho_light, light), 1.0);
}

TEST(CalibrationPositions, TriangulatesRaysAndReportsResiduals) {
  const Vec3 led(120, -250, 300);
  std::vector<Ray> rays;
  for (const Vec3& origin : {Vec3(-20, 0, 0), Vec3(20, 5, 0), Vec3(0, -20, 30)})
    rays.push_back({origin, (led - origin).normalized()});
  const auto t = triangulate(rays);
  ASSERT_TRUE(t);
  EXPECT_LT((t->position_mm - led).norm(), 1e-9);
  EXPECT_LT(t->rms_mm, 1e-9);
  // A ray off by 1 mm at the LED shows in the residual.
  rays[0].direction = (led + Vec3(1, 0, 0) - rays[0].origin).normalized();
  const auto off = triangulate(rays);
  ASSERT_TRUE(off);
  EXPECT_GT(off->rms_mm, 0.1);
  // Parallel rays cannot be triangulated.
  EXPECT_FALSE(triangulate({{Vec3::Zero(), Vec3::UnitZ()}, {Vec3::UnitX(), Vec3::UnitZ()}}));
  EXPECT_FALSE(triangulate({rays[0]}));
}

// The forward model inverts reflect_at, and the maximum-likelihood fit finds
// the LED from exact highlights, with a covariance that grows as the rays
// close up — for both camera models.
TEST(CalibrationPositions, PredictedHighlightsReflectToTheLedAndRefineToIt) {
  CameraGeometry ortho = CameraGeometry::unknown(512, 512);
  ortho.pixel_pitch_mm = 0.2;
  ortho.metric = true;
  CameraGeometry pinhole = ortho;
  pinhole.model = CameraModel::kPinhole;
  pinhole.focal_px = 1500;
  pinhole.position_mm = Vec3(0, 0, 600);
  const Vec3 led(-150, 280, 230);
  for (const CameraGeometry& camera : {ortho, pinhole}) {
    SCOPED_TRACE(camera.model == CameraModel::kPinhole ? "pinhole" : "orthographic");
    std::vector<HighlightObservation> observations;
    for (const Vec3& centre : {Vec3(-30, 0, 0), Vec3(30, 0, 0)}) {
      HighlightObservation o;
      o.sphere.centre_mm = centre;
      o.sphere.radius_mm = 20;
      const auto uv = predict_highlight(o.sphere, camera, led);
      ASSERT_TRUE(uv);
      const auto reflection = reflect_at(o.sphere, camera, *uv);
      ASSERT_TRUE(reflection);
      EXPECT_LT(angle_between_deg(reflection->direction, (led - reflection->point_mm).normalized()), 1e-8);
      o.centre_px = *uv;
      o.covariance_px = Eigen::Matrix2d::Identity() * 0.02 * 0.02;
      observations.push_back(o);
    }
    const auto fit = refine_led_position(observations, camera, led + Vec3(15, -10, 20));
    ASSERT_TRUE(fit);
    EXPECT_LT((fit->position_mm - led).norm(), 1e-6);
    EXPECT_LT(fit->rms_px, 1e-8);
    // 0.02 px on a 100 px sphere, rays meeting at ~7° 400 mm away: millimetres along the rays.
    EXPECT_GT(fit->sigma_mm, 0.3);
    EXPECT_LT(fit->sigma_mm, 5.0);
    // The same LED seen from spheres half as far apart is known half as well.
    std::vector<HighlightObservation> close = observations;
    for (auto& o : close) {
      o.sphere.centre_mm.x() /= 2;
      o.centre_px = *predict_highlight(o.sphere, camera, led);
    }
    const auto close_fit = refine_led_position(close, camera, led);
    ASSERT_TRUE(close_fit);
    EXPECT_NEAR(close_fit->sigma_mm / fit->sigma_mm, 2.0, 0.2);
    // One sphere position cannot place the LED.
    EXPECT_FALSE(refine_led_position({observations[0]}, camera, led));
    EXPECT_FALSE(refine_led_position({observations[0], observations[0]}, camera, led));
  }
}

TEST(CalibrationPositions, RayMeetsTheDomeAtItsRadius) {
  const auto p = intersect_dome({Vec3(10, 0, 5), Vec3(1, 1, 1).normalized()}, Vec3::Zero(), 400);
  ASSERT_TRUE(p);
  EXPECT_NEAR(p->norm(), 400, 1e-9);
  EXPECT_NEAR(((*p - Vec3(10, 0, 5)).normalized() - Vec3(1, 1, 1).normalized()).norm(), 0, 1e-12);
}

TEST(CalibrationPositions, NominalFitRecoversARigidMoveAndOneLedOffset) {
  std::vector<Vec3> nominal, measured;
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(rad_from_deg(2.0), Vec3(0.2, 1, 0.1).normalized()).toRotationMatrix();
  const Vec3 shift(3, -2, 5);
  for (int k = 0; k < 24; ++k) {
    const double a = 2 * kPi * k / 24;
    nominal.emplace_back(400 * std::cos(a) * 0.9, 400 * std::sin(a) * 0.9, 120 + 40 * (k % 3));
    measured.push_back(rotation * nominal.back() + shift);
  }
  measured[5] += Vec3(0, 0, 6);
  const NominalFit fit = fit_to_nominal(nominal, measured);
  EXPECT_NEAR(fit.rotation_deg, 2.0, 0.05);
  EXPECT_LT((fit.translation - shift).norm(), 0.5);
  EXPECT_NEAR(fit.corrections[5].z(), 6, 1.0);  // least squares spreads a little of it over the rest
  EXPECT_GT(fit.max_mm, 5);
  EXPECT_NE(error_of([] { fit_to_nominal({Vec3::Zero()}, {Vec3::Zero()}); }).find("at least 3"),
            std::string::npos);
}

}  // namespace
}  // namespace lightstage::calibration
