// The camera interface's shared parts: URIs, the scheme registry, clock
// domains, CFA bookkeeping under crops.
#include "lightstage/common/camera.hpp"
#include "lightstage/hw/cameras.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>

namespace lightstage::camera {
namespace {

using testing::HasSubstr;

TEST(CameraUri, SplitsSchemeTargetAndOptions) {
  const CameraUri a = parse_camera_uri("v4l2:/dev/video0");
  EXPECT_EQ(a.scheme, "v4l2");
  EXPECT_EQ(a.target, "/dev/video0");
  EXPECT_TRUE(a.options.empty());

  // libcamera ids may hold colons: only the first one splits.
  const CameraUri b = parse_camera_uri(R"(libcamera:\_SB_.PCI0.XHC_.RHUB.HS08-8:1.0-04f2:b6dd)");
  EXPECT_EQ(b.scheme, "libcamera");
  EXPECT_EQ(b.target, R"(\_SB_.PCI0.XHC_.RHUB.HS08-8:1.0-04f2:b6dd)");

  const CameraUri c = parse_camera_uri("v4l2:/dev/video2?exposure_unit_us=14.7&gain_unity=16");
  EXPECT_EQ(c.target, "/dev/video2");
  EXPECT_EQ(c.option("exposure_unit_us"), "14.7");
  EXPECT_EQ(c.option("gain_unity"), "16");
  EXPECT_FALSE(c.option("nope").has_value());

  EXPECT_EQ(parse_camera_uri("libcamera:").target, "");
}

TEST(CameraUri, MalformedUrisAreInputErrorsNamingThem) {
  for (const char* bad : {"/dev/video0", ":x", "v 4l2:/dev/video0", "v4l2:/dev/video0?exposure"}) {
    try {
      parse_camera_uri(bad);
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(bad));
    }
  }
}

class StubCamera final : public Camera {
 public:
  explicit StubCamera(std::string uri) : Camera(std::move(uri)) {}
  CameraInfo info() const override { return {uri(), "stub", "test"}; }
  std::vector<FormatInfo> formats() const override { return {}; }
  std::vector<TriggerMode> trigger_modes() const override { return {TriggerMode::kFreeRun}; }
  CameraConfig default_config() const override { return {}; }
  Validation validate(CameraConfig&) const override { return {}; }
  void configure(const CameraConfig&) override {}
  CameraConfig configuration() const override { return {}; }
  ControlInfo control_info() const override { return {}; }
  Controls set_controls(const Controls& c) override { return c; }
  void start() override {}
  void stop() override {}
  bool streaming() const override { return true; }
  void trigger() override {}
  std::optional<Frame> wait_frame(std::chrono::milliseconds) override { return std::nullopt; }
};

TEST(CameraRegistry, OpensThroughARegisteredScheme) {
  register_camera_scheme({"stubcam", "stubcam:NAME", "",
                          [](const CameraUri& uri) { return std::make_unique<StubCamera>(uri.uri); },
                          [] {
                            return std::vector<CameraInfo>{{"stubcam:one", "stub", "test"}};
                          }});
  auto cam = open_camera_uri("stubcam:one");
  EXPECT_EQ(cam->uri(), "stubcam:one");
  EXPECT_EQ(cam->info().model, "stub");
  // capture() turns a timeout into an error naming the camera.
  try {
    cam->capture(std::chrono::milliseconds(3));
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_EQ(e.kind(), CameraError::Kind::kTimeout);
    EXPECT_THAT(e.what(), HasSubstr("stubcam:one"));
  }
}

TEST(CameraRegistry, UnknownAndUnavailableSchemes) {
  hw::register_hw_cameras();
  try {
    open_camera_uri("gopro:front");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("gopro:front"));
    EXPECT_THAT(e.what(), HasSubstr("v4l2:/dev/videoN"));
    EXPECT_THAT(e.what(), HasSubstr("libcamera:ID"));
  }
  register_camera_scheme({"ghostcam", "ghostcam:X", "this build has no ghost backend", {}, {}});
  try {
    open_camera_uri("ghostcam:1");
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_EQ(e.kind(), CameraError::Kind::kUnsupported);
    EXPECT_THAT(e.what(), HasSubstr("ghostcam:1"));
    EXPECT_THAT(e.what(), HasSubstr("no ghost backend"));
  }
}

TEST(ClockDomain, BoottimeToMonotonicMatchesNow) {
  const std::int64_t boot = clock_now_ns(ClockDomain::kBoottime);
  const std::int64_t mono = clock_now_ns(ClockDomain::kMonotonic);
  const std::int64_t converted = convert_timestamp_ns(boot, ClockDomain::kBoottime, ClockDomain::kMonotonic);
  EXPECT_NEAR(static_cast<double>(converted), static_cast<double>(mono), 1e6);  // within 1 ms
  // BOOTTIME counts suspend too, so it is never behind MONOTONIC.
  EXPECT_GE(clock_offset_ns(ClockDomain::kMonotonic, ClockDomain::kBoottime), -1000);
  // There and back again.
  const std::int64_t t = 123'456'789'000;
  const std::int64_t round_trip =
      convert_timestamp_ns(convert_timestamp_ns(t, ClockDomain::kBoottime, ClockDomain::kMonotonic),
                           ClockDomain::kMonotonic, ClockDomain::kBoottime);
  EXPECT_NEAR(static_cast<double>(round_trip), static_cast<double>(t), 1e5);
  EXPECT_EQ(convert_timestamp_ns(t, ClockDomain::kMonotonic, ClockDomain::kMonotonic), t);
  EXPECT_THROW(convert_timestamp_ns(t, ClockDomain::kUnknown, ClockDomain::kMonotonic), CameraError);
}

TEST(Cfa, CropOffsetsShiftThePattern) {
  EXPECT_EQ(cfa_at(Cfa::kRGGB, 0, 0), Cfa::kRGGB);
  EXPECT_EQ(cfa_at(Cfa::kRGGB, 1, 0), Cfa::kGRBG);
  EXPECT_EQ(cfa_at(Cfa::kRGGB, 0, 1), Cfa::kGBRG);
  EXPECT_EQ(cfa_at(Cfa::kRGGB, 1, 1), Cfa::kBGGR);
  EXPECT_EQ(cfa_at(Cfa::kBGGR, 3, 5), Cfa::kRGGB);
  EXPECT_EQ(cfa_at(Cfa::kGRBG, 2, 1), Cfa::kBGGR);
  EXPECT_EQ(cfa_at(Cfa::kNone, 1, 1), Cfa::kNone);
}

TEST(Cfa, CropFrameChecksBounds) {
  Frame f;
  f.image = cv::Mat(4, 6, CV_16UC1, cv::Scalar(0));
  f.image.at<std::uint16_t>(1, 3) = 77;
  f.cfa = Cfa::kBGGR;
  crop_frame(f, {3, 1, 2, 2}, "test:cam");
  EXPECT_EQ(f.image.size(), cv::Size(2, 2));
  EXPECT_EQ(f.image.at<std::uint16_t>(0, 0), 77);
  EXPECT_EQ(f.cfa, Cfa::kRGGB);
  try {
    crop_frame(f, {1, 1, 2, 2}, "test:cam");
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_THAT(e.what(), HasSubstr("test:cam"));
    EXPECT_THAT(e.what(), HasSubstr("2x2+1+1"));
  }
}

}  // namespace
}  // namespace lightstage::camera
