#include "lightstage/host/radiometry.hpp"

#include "lightstage/common/error.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <vector>

namespace lightstage {
namespace {

constexpr double kR = 0.2989, kG = 0.5870, kB = 0.1140;

ImageStack colour_stack() {
  ImageStack stack;
  for (int i = 0; i < 3; ++i) {
    Frame frame;
    frame.filename = "f" + std::to_string(i);
    frame.image = cv::Mat(2, 3, CV_16UC3, cv::Scalar::all(0));
    frame.light_direction = Vec3(i == 0 ? 2.0 : 0.0, i == 1 ? 2.0 : 0.0, 1.0);  // not unit on purpose
    frame.light_intensity = Vec3(2.0, 4.0, 8.0);
    stack.frames.push_back(frame);
  }
  return stack;
}

TEST(HostRadiometry, ColourIsNormalisedPerChannelThenGreyBt601InBgrOrder) {
  ImageStack stack = colour_stack();
  // Pixel (x=1, y=0): B=6553.5-ish, only red at (x=2, y=1).
  stack.frames[0].image.at<cv::Vec3w>(0, 1) = cv::Vec3w(1000, 2000, 3000);  // B, G, R
  stack.frames[0].image.at<cv::Vec3w>(1, 2) = cv::Vec3w(0, 0, 65535);
  const Observations obs = make_observations(stack);
  ASSERT_EQ(obs.pixel_count(), 6u);  // no mask: every pixel, row-major
  EXPECT_EQ(obs.pixels[1], cv::Point(1, 0));
  EXPECT_EQ(obs.pixels[5], cv::Point(2, 1));
  const double expected = kR * 3000 / 65535.0 / 2.0 + kG * 2000 / 65535.0 / 4.0 + kB * 1000 / 65535.0 / 8.0;
  EXPECT_NEAR(obs.intensities(1, 0), expected, 1e-7);
  EXPECT_NEAR(obs.intensities(5, 0), kR / 2.0, 1e-7);  // red holds R, divided by the red intensity
  EXPECT_TRUE(obs.saturated(5, 0));
  EXPECT_FALSE(obs.saturated(1, 0));
  EXPECT_EQ(obs.intensities(0, 1), 0.0f);
  // Lights are unit.
  EXPECT_NEAR(obs.lights.row(0).norm(), 1.0, 1e-12);
  EXPECT_NEAR(obs.lights(0, 0), 2.0 / std::sqrt(5.0), 1e-12);
}

// A colour pixel's chroma is its diffuse colour even where a white highlight
// lights some frames brighter than the rest, a saturated frame is left out,
// and the chroma's BT.601 grey is 1.
TEST(HostRadiometry, ChromaIsTheMedianColourOfTheLitFramesAndIgnoresAWhiteHighlight) {
  ImageStack stack;
  const cv::Vec3d diffuse(0.2, 0.5, 0.9);  // B, G, R shares of the albedo
  const double shading[] = {0.2, 0.35, 0.5, 0.6, 0.45, 0.3, 0.25, 0.4, 0.55};
  for (int i = 0; i < 9; ++i) {
    Frame frame;
    frame.filename = "f" + std::to_string(i);
    frame.image = cv::Mat(1, 2, CV_16UC3, cv::Scalar::all(0));
    frame.light_direction = Vec3(std::cos(i), std::sin(i), 1.0);
    cv::Vec3d value = diffuse * shading[i];
    if (i == 3 || i == 4) value += cv::Vec3d::all(0.8);  // a white highlight in two frames of nine
    for (int c = 0; c < 3; ++c)
      frame.image.at<cv::Vec3w>(0, 0)[c] = cv::saturate_cast<std::uint16_t>(value[c] * 30000);
    frame.image.at<cv::Vec3w>(0, 1) = i == 5 ? cv::Vec3w(65535, 65535, 65535) : cv::Vec3w(100, 100, 100);
    stack.frames.push_back(frame);
  }
  const Observations obs = make_observations(stack);
  ASSERT_EQ(obs.chroma.rows(), 2);
  const double grey = kR * diffuse[2] + kG * diffuse[1] + kB * diffuse[0];
  EXPECT_NEAR(obs.chroma(0, 0), diffuse[2] / grey, 1e-3);  // r
  EXPECT_NEAR(obs.chroma(0, 1), diffuse[1] / grey, 1e-3);  // g
  EXPECT_NEAR(obs.chroma(0, 2), diffuse[0] / grey, 1e-3);  // b
  EXPECT_NEAR(kR * obs.chroma(0, 0) + kG * obs.chroma(0, 1) + kB * obs.chroma(0, 2), 1.0, 1e-6);
  // Grey apart from one saturated (white, clipped) frame: neutral.
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(obs.chroma(1, c), 1.0 / (kR + kG + kB), 1e-6) << c;
  // As an image: BGR, zero where not solved.
  cv::Mat solved(1, 2, CV_8UC1, cv::Scalar::all(255));
  solved.at<std::uint8_t>(0, 1) = 0;
  const cv::Mat image = chroma_image(obs, solved);
  ASSERT_EQ(image.type(), CV_32FC3);
  EXPECT_FLOAT_EQ(image.at<cv::Vec3f>(0, 0)[0], obs.chroma(0, 2));
  EXPECT_FLOAT_EQ(image.at<cv::Vec3f>(0, 0)[2], obs.chroma(0, 0));
  EXPECT_EQ(image.at<cv::Vec3f>(0, 1), cv::Vec3f(0, 0, 0));
}

// Pixels whose ratios number differently (a dark pixel, one lit by a few
// frames, clipped frames, channels that tie) in one stack, several to a
// vector lane group and a group left part empty: each pixel's chroma is the
// definition's, the per-channel median (nth_element) of its counted frames.
TEST(HostRadiometry, EveryPixelsChromaIsTheMedianOfItsOwnCountedFrames) {
  constexpr int kWidth = 13, kHeight = 3, kFrames = 40;  // 39 pixels: four groups of 8 and 7
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> level(0, 65535);
  ImageStack stack;
  for (int i = 0; i < kFrames; ++i) {
    Frame frame;
    frame.filename = "f" + std::to_string(i);
    frame.image = cv::Mat(kHeight, kWidth, CV_16UC3);
    frame.light_direction = Vec3(std::cos(i), std::sin(i), 1.0);
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        cv::Vec3w& px = frame.image.at<cv::Vec3w>(y, x);
        const int pixel = y * kWidth + x;
        for (int c = 0; c < 3; ++c)
          px[c] = static_cast<std::uint16_t>(level(rng) >> (pixel % 5 == 0 ? 12 : 0));
        if (pixel % 7 == 0 && i % (1 + pixel % 9) != 0) px = cv::Vec3w(0, 0, 0);  // lit by a few frames
        if (pixel % 4 == 1) px[1] = px[2];                                        // ties
        if (pixel == 0) px = cv::Vec3w(0, 0, 0);                                  // never lit
        if (pixel % 3 == 2 && i % 4 == 0) px[i % 3] = 65535;                      // clipped
      }
    }
    stack.frames.push_back(frame);
  }
  RadiometryOptions one_thread;  // the pixels in groups of 8 as they come, not split between threads
  one_thread.threads = 1;
  const Observations obs = make_observations(stack, one_thread);
  ASSERT_EQ(obs.chroma.rows(), kWidth * kHeight);
  EXPECT_GT(obs.saturated.count(), 0);
  for (Eigen::Index p = 0; p < obs.chroma.rows(); ++p) {
    const cv::Point at = obs.pixels[static_cast<std::size_t>(p)];
    std::vector<double> grey(kFrames);
    double brightest = 0;
    for (int j = 0; j < kFrames; ++j) {
      const cv::Vec3w px = stack.frames[static_cast<std::size_t>(j)].image.at<cv::Vec3w>(at);
      grey[static_cast<std::size_t>(j)] = kR * static_cast<float>(px[2] * (1.0 / 65535.0)) +
                                          kG * static_cast<float>(px[1] * (1.0 / 65535.0)) +
                                          kB * static_cast<float>(px[0] * (1.0 / 65535.0));
      if (!obs.saturated(p, j)) brightest = std::max(brightest, grey[static_cast<std::size_t>(j)]);
    }
    std::array<std::vector<float>, 3> ratios;
    for (int j = 0; j < kFrames && brightest > 0; ++j) {
      const double y = grey[static_cast<std::size_t>(j)];
      if (obs.saturated(p, j) || !(y >= kChromaMinShare * brightest)) continue;
      const cv::Vec3w px = stack.frames[static_cast<std::size_t>(j)].image.at<cv::Vec3w>(at);
      for (int c = 0; c < 3; ++c)
        ratios[static_cast<std::size_t>(c)].push_back(
            static_cast<float>(static_cast<float>(px[2 - c] * (1.0 / 65535.0)) / y));
    }
    Eigen::RowVector3f expected = Eigen::RowVector3f::Ones();
    if (!ratios[0].empty()) {
      Eigen::RowVector3d median;
      for (int c = 0; c < 3; ++c) {
        auto& r = ratios[static_cast<std::size_t>(c)];
        std::nth_element(r.begin(), r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2), r.end());
        median[c] = std::max(0.0f, r[r.size() / 2]);
      }
      const double median_grey = kR * median[0] + kG * median[1] + kB * median[2];
      if (median_grey > 0) expected = (median / median_grey).cast<float>();
    }
    EXPECT_EQ(obs.chroma.row(p), expected) << "pixel " << p;
  }
}

TEST(HostRadiometry, GreyStacksHaveNoChroma) {
  ImageStack stack = colour_stack();
  for (auto& frame : stack.frames) frame.image = cv::Mat(2, 3, CV_16UC1, cv::Scalar::all(500));
  const Observations obs = make_observations(stack);
  EXPECT_EQ(obs.chroma.rows(), 0);
  EXPECT_TRUE(chroma_image(obs).empty());
}

TEST(HostRadiometry, ClampsToOneUnlessAskedNot) {
  ImageStack stack = colour_stack();
  for (auto& frame : stack.frames) frame.light_intensity = Vec3(0.25, 0.25, 0.25);
  stack.frames[1].image.at<cv::Vec3w>(0, 0) = cv::Vec3w(40000, 40000, 40000);
  EXPECT_EQ(make_observations(stack).intensities(0, 1), 1.0f);
  RadiometryOptions options;
  options.clamp_to_one = false;
  EXPECT_NEAR(make_observations(stack, options).intensities(0, 1), (kR + kG + kB) * 40000 / 65535.0 / 0.25,
              1e-5);
}

TEST(HostRadiometry, GreyEightBitWithBlackLevelSaturationAndMask) {
  ImageStack stack;
  for (int i = 0; i < 3; ++i) {
    Frame frame;
    frame.image = cv::Mat(3, 3, CV_8UC1, cv::Scalar::all(100));
    frame.black_level = 10;
    frame.saturation_level = 200;
    frame.light_intensity = Vec3(2, 2, 2);
    frame.light_direction = Vec3(0, 0, 1);
    stack.frames.push_back(frame);
  }
  stack.frames[2].image.at<std::uint8_t>(1, 1) = 200;
  stack.mask = cv::Mat(3, 3, CV_8UC1, cv::Scalar::all(0));
  stack.mask.at<std::uint8_t>(1, 1) = 255;
  stack.mask.at<std::uint8_t>(2, 0) = 1;  // any nonzero is inside
  const Observations obs = make_observations(stack);
  ASSERT_EQ(obs.pixel_count(), 2u);
  EXPECT_EQ(obs.pixels[0], cv::Point(1, 1));
  EXPECT_EQ(obs.pixels[1], cv::Point(0, 2));
  EXPECT_EQ(obs.mask.at<std::uint8_t>(2, 0), 255);
  // Grey images divide by the grey of the intensity, with the BT.601 weights
  // normalised to sum to 1: a grey light of 2 divides by exactly 2.
  EXPECT_NEAR(obs.intensities(0, 0), 90 / 255.0 / 2, 1e-6);
  EXPECT_TRUE(obs.saturated(0, 2));
  EXPECT_FALSE(obs.saturated(0, 1));
  EXPECT_FALSE(obs.saturated(1, 2));
}

TEST(HostRadiometry, RejectsInconsistentStacks) {
  ImageStack stack = colour_stack();
  stack.frames[2].image = cv::Mat(2, 3, CV_8UC3, cv::Scalar::all(0));
  EXPECT_THROW(make_observations(stack), InputError);
  stack = colour_stack();
  stack.mask = cv::Mat(5, 5, CV_8UC1, cv::Scalar::all(255));
  EXPECT_THROW(make_observations(stack), InputError);
  EXPECT_THROW(make_observations(ImageStack{}), InputError);
  stack = colour_stack();
  stack.frames[1].dark = cv::Mat(3, 3, CV_16UC3, cv::Scalar::all(0));  // another size
  EXPECT_THROW(make_observations(stack), InputError);
  stack.frames[1].dark = cv::Mat(2, 3, CV_16UC1, cv::Scalar::all(0));  // another channel count
  EXPECT_THROW(make_observations(stack), InputError);
}

// A sensor's dark signal is not flat: a gradient (amplifier glow), column
// offsets and hot pixels. Subtracting the averaged dark frame pixel by pixel
// gives back the signal; the dark's mean as a scalar black level leaves the
// pattern in it.
TEST(HostRadiometry, PerPixelDarkRecoversTheSignalWhereTheScalarBlackLevelCannot) {
  constexpr int kWidth = 40, kHeight = 30;
  cv::Mat dark(kHeight, kWidth, CV_16UC1), signal(kHeight, kWidth, CV_64FC1);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      double d = 400 + 60.0 * x + 25.0 * y + (x % 4 == 0 ? 300 : 0);  // glow + column offsets
      if ((x * 7 + y * 3) % 97 == 0) d += 9000;                       // hot pixels
      dark.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(d);
      signal.at<double>(y, x) = 2000 + 30.0 * ((x * 13 + y * 5) % 40);
    }
  }
  ImageStack stack;
  for (int i = 0; i < 3; ++i) {
    Frame frame;
    frame.image = cv::Mat(kHeight, kWidth, CV_16UC1);
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x)
        frame.image.at<std::uint16_t>(y, x) =
            static_cast<std::uint16_t>(dark.at<std::uint16_t>(y, x) + (i + 1) * signal.at<double>(y, x));
    }
    frame.black_level = cv::mean(dark)[0];  // what a capture without per-pixel darks subtracts
    frame.dark = dark;
    frame.dark_file = "dark_1000us.png";
    stack.frames.push_back(frame);
  }
  RadiometryOptions options;
  options.clamp_to_one = false;
  const auto worst_error = [&](const Observations& obs) {
    double worst = 0;
    for (std::size_t p = 0; p < obs.pixel_count(); ++p) {
      for (Eigen::Index j = 0; j < 3; ++j) {
        const double truth = static_cast<double>(j + 1) * signal.at<double>(obs.pixels[p]) / 65535.0;
        worst = std::max(worst, std::abs(obs.intensities(static_cast<Eigen::Index>(p), j) - truth) / truth);
      }
    }
    return worst;
  };
  const double per_pixel = worst_error(make_observations(stack, options));
  ImageStack scalar = stack;
  for (Frame& frame : scalar.frames) frame.dark.release();  // DiLiGenT-style: black level only
  const double scalar_only = worst_error(make_observations(scalar, options));
  EXPECT_LT(per_pixel, 1e-6);
  EXPECT_GT(scalar_only, 1.0) << "the hot pixels alone are several times the signal";
  RecordProperty("per_pixel_dark_worst_relative_error", std::to_string(per_pixel));
  RecordProperty("scalar_black_worst_relative_error", std::to_string(scalar_only));
}

TEST(HostRadiometry, ColourDarksAreSubtractedChannelByChannel) {
  ImageStack stack = colour_stack();
  cv::Mat dark(2, 3, CV_16UC3, cv::Scalar(100, 200, 300));  // B, G, R
  dark.at<cv::Vec3w>(0, 1) = cv::Vec3w(1000, 500, 4000);
  for (Frame& frame : stack.frames) {
    frame.dark = dark;
    frame.dark_file = "dark.png";
    frame.black_level = 999;  // ignored: the dark replaces it
  }
  stack.frames[0].image.at<cv::Vec3w>(0, 1) = cv::Vec3w(2000, 2500, 7000);
  const Observations obs = make_observations(stack);
  const double expected = kR * 3000 / 65535.0 / 2.0 + kG * 2000 / 65535.0 / 4.0 + kB * 1000 / 65535.0 / 8.0;
  EXPECT_NEAR(obs.intensities(1, 0), expected, 1e-7);
  // A float stack (linearised frames) with a float dark.
  ImageStack linear;
  for (int i = 0; i < 3; ++i) {
    Frame frame;
    frame.image = cv::Mat(2, 2, CV_32FC1, cv::Scalar::all(0.5));
    frame.dark = cv::Mat(2, 2, CV_32FC1, cv::Scalar::all(0.1));
    frame.dark.at<float>(1, 1) = 0.3f;
    frame.dark_file = "dark.pfm";
    linear.frames.push_back(frame);
  }
  const Observations f = make_observations(linear);
  EXPECT_NEAR(f.intensities(0, 0), 0.4, 1e-6);
  EXPECT_NEAR(f.intensities(3, 2), 0.2, 1e-6);
}

}  // namespace
}  // namespace lightstage
