// The libcamera: backend where no camera exists: the camera manager starts,
// and asking for a camera names the id and lists what there is.
#include "lightstage/common/camera.hpp"
#include "lightstage/hw/cameras.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace lightstage {
namespace {

using camera::CameraError;
using testing::HasSubstr;

#ifdef LIGHTSTAGE_HAVE_LIBCAMERA

TEST(LibcameraCamera, UnknownIdNamesItAndListsTheCameras) {
  const auto cameras = hw::list_cameras();
  try {
    hw::open_camera("libcamera:/base/soc/i2c0mux/i2c@1/imx999@1a");
    ADD_FAILURE() << "opened a camera that cannot exist";
  } catch (const CameraError& e) {
    EXPECT_EQ(e.kind(), CameraError::Kind::kNotFound) << e.what();
    EXPECT_THAT(e.what(), HasSubstr("libcamera:/base/soc/i2c0mux/i2c@1/imx999@1a"));
    bool any_libcamera = false;
    for (const auto& c : cameras) any_libcamera |= c.uri.rfind("libcamera:", 0) == 0;
    if (!any_libcamera) {
      EXPECT_THAT(e.what(), HasSubstr("libcamera sees no camera"));
      EXPECT_THAT(e.what(), HasSubstr("libcamera-ipa"));
    } else {
      EXPECT_THAT(e.what(), HasSubstr("cameras: libcamera:"));
    }
  }
}

TEST(LibcameraCamera, FirstCameraWhenNoneIsNamed) {
  bool any = false;
  for (const auto& c : hw::list_cameras()) any |= c.uri.rfind("libcamera:", 0) == 0;
  if (any) GTEST_SKIP() << "this machine has a libcamera camera";
  try {
    hw::open_camera("libcamera:");
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_EQ(e.kind(), CameraError::Kind::kNotFound);
    EXPECT_THAT(e.what(), HasSubstr("no camera"));
  }
}

TEST(LibcameraCamera, RejectsOptions) {
  EXPECT_THROW(hw::open_camera("libcamera:x?exposure_unit_us=3"), InputError);
}

#else

TEST(LibcameraCamera, AbsentBackendSaysSo) {
  try {
    hw::open_camera("libcamera:x");
    ADD_FAILURE();
  } catch (const CameraError& e) {
    EXPECT_EQ(e.kind(), CameraError::Kind::kUnsupported);
    EXPECT_THAT(e.what(), HasSubstr("libcamera"));
  }
}

#endif

}  // namespace
}  // namespace lightstage
