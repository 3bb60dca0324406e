// The v4l2: backend against a fake device (fake_v4l2_device.hpp): format
// negotiation, the mmap buffer cycle, sequence numbers and timestamps, lost
// frames, unplugging, exposure and gain mapping, software trigger.
#include "fake_v4l2_device.hpp"

#include "lightstage/hw/cameras.hpp"
#include "lightstage/hw/v4l2_camera.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <memory>

namespace lightstage {
namespace {

using camera::CameraError;
using testing::HasSubstr;
using namespace std::chrono_literals;

constexpr std::int64_t kSecond = 1'000'000'000;

std::unique_ptr<camera::Camera> open_fake(const std::shared_ptr<test::FakeV4l2Device>& dev,
                                          const std::string& uri = "v4l2:/dev/video0") {
  return hw::open_v4l2_camera(camera::parse_camera_uri(uri), dev);
}

template <typename F>
CameraError::Kind error_kind(F&& f, std::string* message = nullptr) {
  try {
    f();
  } catch (const CameraError& e) {
    if (message) *message = e.what();
    return e.kind();
  }
  ADD_FAILURE() << "no CameraError thrown";
  return CameraError::Kind::kFailed;
}

int count(const std::vector<std::string>& log, const std::string& what) {
  return static_cast<int>(std::count(log.begin(), log.end(), what));
}

TEST(V4l2Camera, ListsTheFormatsItCanUnpack) {
  auto dev = std::make_shared<test::FakeV4l2Device>();
  auto cam = open_fake(dev);
  EXPECT_EQ(cam->info().model, "Fake Sensor");
  EXPECT_EQ(cam->info().driver, "fakecam");
  const auto formats = cam->formats();
  std::vector<std::string> names;
  for (const auto& f : formats) names.push_back(f.pixel_format);
  EXPECT_THAT(names, testing::ElementsAre("GREY", "Y10", "SRGGB12", "YUYV"));  // MJPG skipped
  EXPECT_EQ(formats[0].sizes.size(), 2u);
  EXPECT_EQ(formats[0].sizes[1].max, (camera::Size{320, 240}));
  EXPECT_EQ(formats[1].bit_depth, 10);
  EXPECT_EQ(formats[2].bit_depth, 12);
  EXPECT_EQ(formats[2].cfa, camera::Cfa::kRGGB);
  // The default is what the driver had in force.
  EXPECT_EQ(cam->default_config().pixel_format, "GREY");
  EXPECT_EQ(cam->default_config().size, (camera::Size{640, 480}));
}

TEST(V4l2Camera, OpeningChangesNothingUntilStart) {
  auto dev = std::make_shared<test::FakeV4l2Device>();
  dev->fmt.pixelformat = V4L2_PIX_FMT_MJPEG;  // the driver's current format is one we cannot unpack
  auto cam = open_fake(dev);
  EXPECT_EQ(count(dev->log, "S_FMT"), 0);  // listing devices must not reconfigure them
  EXPECT_EQ(cam->default_config().pixel_format, "GREY");
  cam->start();
  EXPECT_EQ(count(dev->log, "S_FMT"), 1);
  EXPECT_EQ(dev->fmt.pixelformat, static_cast<std::uint32_t>(V4L2_PIX_FMT_GREY));
}

TEST(V4l2Camera, OpenErrorsNameTheUri) {
  auto dev = std::make_shared<test::FakeV4l2Device>();
  std::string message;
  EXPECT_EQ(error_kind([&] { open_fake(dev, "v4l2:/dev/video7"); }, &message), CameraError::Kind::kNotFound);
  EXPECT_THAT(message, HasSubstr("v4l2:/dev/video7"));

  dev->open_errno = EACCES;
  EXPECT_EQ(error_kind([&] { open_fake(dev); }, &message), CameraError::Kind::kFailed);
  EXPECT_THAT(message, HasSubstr("group 'video'"));

  dev->open_errno = 0;
  dev->capabilities = V4L2_CAP_VIDEO_CAPTURE_MPLANE | V4L2_CAP_STREAMING;
  EXPECT_EQ(error_kind([&] { open_fake(dev); }, &message), CameraError::Kind::kUnsupported);
  EXPECT_THAT(message, HasSubstr("multi-planar"));
  EXPECT_FALSE(dev->is_open);  // closed again on failure

  dev->capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  dev->formats = {{V4L2_PIX_FMT_MJPEG, {{640, 480}}}};
  EXPECT_EQ(error_kind([&] { open_fake(dev); }, &message), CameraError::Kind::kUnsupported);
  EXPECT_THAT(message, HasSubstr("MJPG"));
}

TEST(V4l2Camera, UriTargetsAndOptions) {
  auto dev = std::make_shared<test::FakeV4l2Device>();
  EXPECT_NO_THROW(open_fake(dev, "v4l2:0"));  // v4l2:N is /dev/videoN
  EXPECT_THROW(open_fake(dev, "v4l2:"), InputError);
  EXPECT_THROW(open_fake(dev, "v4l2:video0"), InputError);
  EXPECT_THROW(open_fake(dev, "v4l2:/dev/video0?colour=blue"), InputError);
  EXPECT_THROW(open_fake(dev, "v4l2:/dev/video0?exposure_unit_us=-3"), InputError);
}

TEST(V4l2Camera, ValidationAdjustsAndConfigureAppliesOnlyValid) {
  auto dev = std::make_shared<test::FakeV4l2Device>();
  auto cam = open_fake(dev);

  camera::CameraConfig config;
  config.pixel_format = "Y16";  // not offered
  camera::Validation v = cam->validate(config);
  EXPECT_EQ(v.status, camera::ConfigStatus::kInvalid);
  EXPECT_THAT(v.message(), HasSubstr("'Y16'"));
  EXPECT_THAT(v.message(), HasSubstr("GREY, Y10, SRGGB12, YUYV"));

  config = {};
  config.pixel_format = "GREY";
  config.size = {330, 250};
  config.roi = camera::Roi{300, 200, 100, 100};
  v = cam->validate(config);
  EXPECT_EQ(v.status, camera::ConfigStatus::kAdjusted);
  EXPECT_EQ(config.size, (camera::Size{320, 240}));
  EXPECT_EQ(*config.roi, (camera::Roi{300, 200, 20, 40}));
  ASSERT_EQ(v.notes.size(), 2u);
  EXPECT_THAT(v.notes[0], HasSubstr("330x250"));

  // Unvalidated: refused with the reasons; validated: applied.
  camera::CameraConfig raw;
  raw.pixel_format = "GREY";
  raw.size = {330, 250};
  std::string message;
  EXPECT_EQ(error_kind([&] { cam->configure(raw); }, &message), CameraError::Kind::kFailed);
  EXPECT_THAT(message, HasSubstr("adjusted"));
  EXPECT_EQ(count(dev->log, "S_FMT"), 0);
  EXPECT_EQ(cam->validate(config).status, camera::ConfigStatus::kValid);
  cam->configure(config);
  EXPECT_EQ(count(dev->log, "S_FMT"), 1);
  EXPECT_EQ(dev->fmt.width, 320u);
  EXPECT_EQ(cam->configuration().size, (camera::Size{320, 240}));
}

TEST(V4l2Camera, BufferCycleSequenceAndTimestamps) {
  auto dev = std::make_shared<test::FakeV4l2Device>();
  auto cam = open_fake(dev);
  camera::CameraConfig config = cam->default_config();
  config.buffer_count = 3;
  ASSERT_EQ(cam->validate(config).status, camera::ConfigStatus::kValid);
  cam->configure(config);
  cam->start();
  EXPECT_TRUE(cam->streaming());
  EXPECT_EQ(count(dev->log, "REQBUFS 3"), 1);
  EXPECT_EQ(dev->mapped, 3);
  EXPECT_EQ(dev->queued.size(), 3u);

  for (std::uint32_t i = 0; i < 5; ++i) {
    dev->sensor.push_back(
        dev->frame_of_rows(i, 10 * kSecond + i * 33'000'000, std::vector<std::uint8_t>(640, i * 10)));
  }
  for (std::uint32_t i = 0; i < 5; ++i) {
    const camera::Frame f = cam->capture(1s);
    EXPECT_EQ(f.sequence, i);
    EXPECT_EQ(f.timestamp_ns, 10 * kSecond + i * 33'000'000);
    EXPECT_EQ(f.clock, camera::ClockDomain::kMonotonic);
    EXPECT_EQ(f.timestamp_point, camera::TimestampPoint::kEndOfFrame);
    EXPECT_EQ(f.image.type(), CV_8UC1);
    EXPECT_EQ(f.image.size(), cv::Size(640, 480));
    EXPECT_EQ(f.image.at<std::uint8_t>(479, 639), i * 10);
    EXPECT_EQ(f.pixel_format, "GREY");
    EXPECT_EQ(dev->queued.size(), 3u);  // every buffer goes back to the driver
  }
  // Frames are values: the next frame overwriting a buffer leaves the earlier frame alone.
  dev->sensor.push_back(dev->frame_of_rows(5, 11 * kSecond, std::vector<std::uint8_t>(640, 7)));
  dev->sensor.push_back(dev->frame_of_rows(6, 12 * kSecond, std::vector<std::uint8_t>(640, 9)));
  const camera::Frame first = cam->capture(1s);
  const camera::Frame second = cam->capture(1s);
  EXPECT_EQ(first.image.at<std::uint8_t>(0, 0), 7);
  EXPECT_EQ(second.image.at<std::uint8_t>(0, 0), 9);

  cam->stop();
  EXPECT_FALSE(cam->streaming());
  EXPECT_EQ(count(dev->log, "STREAMOFF"), 1);
  EXPECT_EQ(dev->mapped, 0);
  EXPECT_EQ(count(dev->log, "REQBUFS 0"), 1);
  cam->stop();  // idempotent
  EXPECT_EQ(count(dev->log, "STREAMOFF"), 1);
  EXPECT_THROW(cam->wait_frame(1ms), CameraError);  // not streaming
}

TEST(V4l2Camera, LostFramesShowAsSequenceGaps) {
  auto dev = std::make_shared<test::FakeV4l2Device>();
  auto cam = open_fake(dev);
  cam->start();
  const std::vector<std::uint8_t> row(640, 1);
  dev->sensor.push_back(dev->frame_of_rows(0, 1 * kSecond, row));
  dev->sensor.push_back(dev->frame_of_rows(1, 2 * kSecond, row));
  dev->sensor.push_back(dev->frame_of_rows(3, 4 * kSecond, row));  // 2 never came
  auto corrupt = dev->frame_of_rows(4, 5 * kSecond, row);
  corrupt.error = true;  // the driver flags it: skipped
  dev->sensor.push_back(corrupt);
  dev->sensor.push_back(dev->frame_of_rows(5, 6 * kSecond, row));
  std::vector<std::uint64_t> seen;
  while (auto f = cam->wait_frame(10ms)) seen.push_back(f->sequence);
  EXPECT_THAT(seen, testing::ElementsAre(0, 1, 3, 5));
}

TEST(V4l2Camera, SequenceNumbersWidenAcrossWrapAround) {
  auto dev = std::make_shared<test::FakeV4l2Device>();
  auto cam = open_fake(dev);
  cam->start();
  const std::vector<std::uint8_t> row(640, 1);
  dev->sensor.push_back(dev->frame_of_rows(0xffffffffu, 1 * kSecond, row));
  dev->sensor.push_back(dev->frame_of_rows(0, 2 * kSecond, row));
  EXPECT_EQ(cam->capture(1s).sequence, 0xffffffffull);
  EXPECT_EQ(cam->capture(1s).sequence, 0x100000000ull);
}

TEST(V4l2Camera, TimeoutIsNulloptOrANamedError) {
  auto dev = std::make_shared<test::FakeV4l2Device>();
  auto cam = open_fake(dev);
  cam->start();
  EXPECT_FALSE(cam->wait_frame(5ms).has_value());
  std::string message;
  EXPECT_EQ(error_kind([&] { cam->capture(5ms); }, &message), CameraError::Kind::kTimeout);
  EXPECT_THAT(message, HasSubstr("v4l2:/dev/video0"));
  EXPECT_THAT(message, HasSubstr("5 ms"));
}

TEST(V4l2Camera, UnplugIsACleanDisconnectError) {
  auto dev = std::make_shared<test::FakeV4l2Device>();
  auto cam = open_fake(dev);
  cam->start();
  dev->sensor.push_back(dev->frame_of_rows(0, kSecond, std::vector<std::uint8_t>(640, 1)));
  EXPECT_EQ(cam->capture(1s).sequence, 0u);
  dev->unplugged = true;
  std::string message;
  EXPECT_EQ(error_kind([&] { cam->wait_frame(10ms); }, &message), CameraError::Kind::kDisconnected);
  EXPECT_THAT(message, HasSubstr("v4l2:/dev/video0"));
  EXPECT_THAT(message, HasSubstr("disconnected"));
  EXPECT_NO_THROW(cam->stop());
  cam.reset();  // the destructor copes with a vanished device
  EXPECT_EQ(dev->mapped, 0);
  EXPECT_FALSE(dev->is_open);
}

TEST(V4l2Camera, ExposureAbsoluteIsIn100UsAndGainRelativeToUnity) {
  auto dev = std::make_shared<test::FakeV4l2Device>();
  dev->controls[V4L2_CID_EXPOSURE_AUTO] = {0, 3, 1, V4L2_EXPOSURE_APERTURE_PRIORITY,
                                           V4L2_EXPOSURE_APERTURE_PRIORITY};
  dev->controls[V4L2_CID_EXPOSURE_ABSOLUTE] = {1, 5000, 1, 100, 100};
  dev->controls[V4L2_CID_ANALOGUE_GAIN] = {16, 248, 1, 16, 16};
  auto cam = open_fake(dev);
  const camera::ControlInfo info = cam->control_info();
  EXPECT_DOUBLE_EQ(info.exposure_min_us, 100);
  EXPECT_DOUBLE_EQ(info.exposure_max_us, 500000);
  EXPECT_DOUBLE_EQ(info.gain_min, 1.0);
  EXPECT_DOUBLE_EQ(info.gain_max, 15.5);
  EXPECT_GT(info.latency_frames, 0);

  const camera::Controls applied = cam->set_controls({8049.0, 2.0});
  EXPECT_EQ(dev->controls[V4L2_CID_EXPOSURE_AUTO].value, V4L2_EXPOSURE_MANUAL);
  EXPECT_EQ(dev->controls[V4L2_CID_EXPOSURE_ABSOLUTE].value, 80);
  EXPECT_EQ(dev->controls[V4L2_CID_ANALOGUE_GAIN].value, 32);
  EXPECT_DOUBLE_EQ(*applied.exposure_us, 8000);  // rounded to the 100 µs step
  EXPECT_DOUBLE_EQ(*applied.analogue_gain, 2.0);

  std::string message;
  EXPECT_EQ(error_kind([&] { cam->set_controls({.exposure_us = 1e7}); }, &message),
            CameraError::Kind::kFailed);
  EXPECT_THAT(message, HasSubstr("exposure_us 10000000"));
  EXPECT_THAT(message, HasSubstr("[100, 500000]"));
  EXPECT_EQ(dev->controls[V4L2_CID_EXPOSURE_ABSOLUTE].value, 80);  // untouched

  // Frames carry the values in force (not reported by the device).
  cam->start();
  dev->sensor.push_back(dev->frame_of_rows(0, kSecond, std::vector<std::uint8_t>(640, 1)));
  const camera::Frame f = cam->capture(1s);
  EXPECT_DOUBLE_EQ(f.exposure_us, 8000);
  EXPECT_DOUBLE_EQ(f.analogue_gain, 2.0);
  EXPECT_FALSE(f.controls_reported);
}

TEST(V4l2Camera, ExposureInLinesUsesPixelRateAndBlanking) {
  auto dev = std::make_shared<test::FakeV4l2Device>();
  dev->controls[V4L2_CID_EXPOSURE] = {4, 2000, 1, 100, 100};
  dev->controls[V4L2_CID_HBLANK] = {160, 160, 1, 160, 160};
  dev->controls[V4L2_CID_GAIN] = {0, 255, 1, 0, 0};
  dev->pixel_rate = 80'000'000;  // (640 + 160) px per line at 80 MHz: 10 µs a line
  auto cam = open_fake(dev);
  cam->set_controls({.exposure_us = 5000, .analogue_gain = 3});
  EXPECT_EQ(dev->controls[V4L2_CID_EXPOSURE].value, 500);
  EXPECT_EQ(dev->controls[V4L2_CID_GAIN].value, 3);  // default 0: unity is 1

  // No pixel rate: the unit must come from the URI.
  dev->pixel_rate = 0;
  auto unknown = open_fake(dev);
  std::string message;
  EXPECT_EQ(error_kind([&] { unknown->set_controls({.exposure_us = 5000}); }, &message),
            CameraError::Kind::kUnsupported);
  EXPECT_THAT(message, HasSubstr("exposure_unit_us"));
  auto told = open_fake(dev, "v4l2:/dev/video0?exposure_unit_us=20&gain_unity=16");
  EXPECT_DOUBLE_EQ(*told->set_controls({.exposure_us = 5000, .analogue_gain = 2}).exposure_us, 5000);
  EXPECT_EQ(dev->controls[V4L2_CID_EXPOSURE].value, 250);
  EXPECT_EQ(dev->controls[V4L2_CID_GAIN].value, 32);
}

TEST(V4l2Camera, DeepAndBayerFramesAreUnpackedWithStride) {
  auto dev = std::make_shared<test::FakeV4l2Device>();
  dev->row_padding = 64;
  auto cam = open_fake(dev);
  camera::CameraConfig config;
  config.pixel_format = "SRGGB12";
  config.roi = camera::Roi{1, 0, 4, 2};  // odd x: the pattern seen becomes GRBG
  ASSERT_EQ(cam->validate(config).status, camera::ConfigStatus::kValid);
  cam->configure(config);
  EXPECT_EQ(dev->fmt.bytesperline, 640u * 2 + 64);
  cam->start();
  std::vector<std::uint8_t> row;
  for (int x = 0; x < 640; ++x) {
    const int v = (x * 7) | 0xF000;  // junk above bit 12 is masked off
    row.push_back(static_cast<std::uint8_t>(v & 0xff));
    row.push_back(static_cast<std::uint8_t>(v >> 8));
  }
  dev->sensor.push_back(dev->frame_of_rows(0, kSecond, row));
  const camera::Frame f = cam->capture(1s);
  EXPECT_EQ(f.image.type(), CV_16UC1);
  EXPECT_EQ(f.image.size(), cv::Size(4, 2));
  EXPECT_EQ(f.bit_depth, 12);
  EXPECT_EQ(f.cfa, camera::Cfa::kGRBG);
  EXPECT_EQ(f.image.at<std::uint16_t>(1, 0), 7);
  EXPECT_EQ(f.image.at<std::uint16_t>(1, 3), 28);
  cam->stop();

  config = {};
  config.pixel_format = "YUYV";
  ASSERT_EQ(cam->validate(config).status, camera::ConfigStatus::kValid);
  cam->configure(config);
  cam->start();
  row.clear();
  for (int x = 0; x < 640; ++x) {
    row.push_back(static_cast<std::uint8_t>(x % 200));  // Y
    row.push_back(128);                                 // U or V
  }
  dev->sensor.push_back(dev->frame_of_rows(0, kSecond, row));
  const camera::Frame y = cam->capture(1s);
  EXPECT_EQ(y.image.type(), CV_8UC1);
  EXPECT_EQ(y.image.at<std::uint8_t>(5, 199), 199);
  EXPECT_EQ(y.image.at<std::uint8_t>(5, 201), 1);
}

TEST(V4l2Camera, SoftwareTriggerDeliversTheFirstFrameExposedAfterIt) {
  auto dev = std::make_shared<test::FakeV4l2Device>();
  dev->timestamps_soe = true;
  auto cam = open_fake(dev);
  camera::CameraConfig config = cam->default_config();
  config.trigger = camera::TriggerMode::kSoftware;
  cam->configure(config);
  EXPECT_THROW(cam->trigger(), CameraError);  // not streaming
  cam->start();
  const std::vector<std::uint8_t> row(640, 1);
  // Before any trigger nothing is delivered.
  dev->sensor.push_back(dev->frame_of_rows(0, camera::clock_now_ns(camera::ClockDomain::kMonotonic), row));
  EXPECT_FALSE(cam->wait_frame(5ms).has_value());
  cam->trigger();
  const std::int64_t now = camera::clock_now_ns(camera::ClockDomain::kMonotonic);
  dev->sensor.push_back(dev->frame_of_rows(1, now - 1'000'000, row));   // exposed before the trigger
  dev->sensor.push_back(dev->frame_of_rows(2, now + 30'000'000, row));  // after
  dev->sensor.push_back(dev->frame_of_rows(3, now + 60'000'000, row));  // not asked for
  const auto f = cam->wait_frame(1s);  // the fake never sleeps: no frame returns at once
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->sequence, 2u);
  EXPECT_EQ(f->timestamp_point, camera::TimestampPoint::kStartOfExposure);
  EXPECT_FALSE(cam->wait_frame(5ms).has_value());

  // Free-run cameras refuse trigger().
  auto free_run = open_fake(std::make_shared<test::FakeV4l2Device>());
  free_run->start();
  EXPECT_EQ(error_kind([&] { free_run->trigger(); }), CameraError::Kind::kUnsupported);
}

TEST(V4l2Camera, UnknownClockIsRecordedAsSuch) {
  auto dev = std::make_shared<test::FakeV4l2Device>();
  dev->timestamps_monotonic = false;
  auto cam = open_fake(dev);
  cam->start();
  dev->sensor.push_back(dev->frame_of_rows(0, kSecond, std::vector<std::uint8_t>(640, 1)));
  EXPECT_EQ(cam->capture(1s).clock, camera::ClockDomain::kUnknown);
}

TEST(V4l2Camera, MissingRealDeviceThroughTheRegistry) {
  // The real system calls: CI has no /dev/video99.
  std::string message;
  EXPECT_EQ(error_kind([&] { hw::open_camera("v4l2:/dev/video99"); }, &message),
            CameraError::Kind::kNotFound);
  EXPECT_THAT(message, HasSubstr("v4l2:/dev/video99"));
}

}  // namespace
}  // namespace lightstage
