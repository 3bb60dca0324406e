// Hostile stack folders: each is refused with one line naming the file, and
// the costly ones (huge declared sizes, repeated names) before any image is decoded.
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/testing/paths.hpp"
#include "stack_fixture.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <fstream>
#include <limits>

namespace lightstage {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
namespace fs = std::filesystem;

class HostHostileStack : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing::scratch_dir() / "stack"; }

  void write_png_stack() const { io::write_stack(dir_, testing::small_stack(4)); }

  void write_pfm_stack() const {
    ImageStack stack = testing::small_stack(4, CV_32FC3);
    for (std::size_t i = 0; i < stack.frames.size(); ++i)
      stack.frames[i].filename = fmt::format("img_{:02}.pfm", i);
    io::write_stack(dir_, stack);
  }

  void write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name, std::ios::binary) << text;
  }

  std::string load_error() const {
    try {
      io::load_stack(dir_);
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
      return message;
    }
    ADD_FAILURE() << "the hostile stack loaded";
    return {};
  }

  fs::path dir_;
};

// A PNG that is only its signature and an IHDR chunk declaring width x height:
// decoding it fails, so a message about its size proves the header was read first.
std::string png_header_only(std::uint32_t width, std::uint32_t height) {
  std::string bytes = "\x89PNG\r\n\x1a\n";
  bytes += std::string("\0\0\0\x0d", 4) + "IHDR";
  for (const std::uint32_t v : {width, height}) {
    for (int shift = 24; shift >= 0; shift -= 8) bytes += static_cast<char>((v >> shift) & 0xff);
  }
  bytes += std::string("\x10\x02\0\0\0", 5) + std::string(4, '\0');  // 16-bit RGB, CRC left zero
  return bytes;
}

TEST_F(HostHostileStack, InfinitePfmPixelIsRefusedWithItsPosition) {
  write_pfm_stack();
  cv::Mat image = io::read_pfm(dir_ / "img_01.pfm");
  image.at<cv::Vec3f>(2, 3)[1] = std::numeric_limits<float>::infinity();
  io::write_pfm(dir_ / "img_01.pfm", image);
  EXPECT_THAT(load_error(), HasSubstr("img_01.pfm: pixel (3, 2) is +Inf"));
}

TEST_F(HostHostileStack, NanPfmPixelIsRefusedWithItsPosition) {
  write_pfm_stack();
  cv::Mat image = io::read_pfm(dir_ / "img_02.pfm");
  image.at<cv::Vec3f>(5, 0)[0] = std::numeric_limits<float>::quiet_NaN();
  io::write_pfm(dir_ / "img_02.pfm", image);
  EXPECT_THAT(load_error(), HasSubstr("img_02.pfm: pixel (0, 5) is NaN"));
}

TEST_F(HostHostileStack, FinitePfmStackLoads) {
  write_pfm_stack();
  EXPECT_EQ(io::load_stack(dir_).frames.size(), 4u);
}

TEST_F(HostHostileStack, RepeatedFileNameIsRefused) {
  write_png_stack();
  write("filenames.txt", "img_00.png\nimg_01.png\nimg_00.png\nimg_03.png\n");
  EXPECT_THAT(load_error(), HasSubstr("filenames.txt:3: 'img_00.png' is listed again (first at line 1)"));
}

TEST_F(HostHostileStack, TooManyListedImagesAreRefused) {
  write_png_stack();
  std::string names;
  for (std::size_t i = 0; i <= io::kMaxStackImages; ++i) names += fmt::format("img_{}.png\n", i);
  write("filenames.txt", names);
  EXPECT_THAT(load_error(), HasSubstr("filenames.txt: 10001 images listed, at most 10000 are read"));
}

TEST_F(HostHostileStack, HugeDeclaredPngIsRefusedBeforeDecoding) {
  write_png_stack();
  write("img_02.png", png_header_only(30000, 30000));
  EXPECT_THAT(load_error(), HasSubstr("img_02.png: image declares 30000x30000, larger than the 16384x16384"));
}

TEST_F(HostHostileStack, SizeFromTheHeaderIsComparedBeforeDecoding) {
  write_png_stack();
  write("img_03.png", png_header_only(5, 5));
  EXPECT_THAT(load_error(), HasSubstr("img_03.png: image is 5x5, but img_00.png is 9x6"));
}

TEST_F(HostHostileStack, ImagesMustFitTheManifestSize) {
  write_png_stack();
  std::ifstream in(dir_ / "manifest.json");
  std::string manifest((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto at = manifest.find("\"width\": 9");
  ASSERT_NE(at, std::string::npos) << manifest;
  manifest.replace(at, 10, "\"width\": 10");
  write("manifest.json", manifest);
  EXPECT_THAT(load_error(),
              HasSubstr("img_00.png: image is 9x6, but " + (dir_ / "manifest.json").string() + " says 10x6"));
}

TEST_F(HostHostileStack, OtherFormatsAreRefusedWhateverTheirName) {
  write_png_stack();
  std::vector<unsigned char> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", cv::Mat(6, 9, CV_8UC3, cv::Scalar::all(90)), jpeg));
  write("img_01.png", std::string(jpeg.begin(), jpeg.end()));
  EXPECT_THAT(load_error(),
              HasSubstr("img_01.png: not a readable image (stack images are PNG, PFM, TIFF or camera RAW)"));
}

TEST_F(HostHostileStack, HugeWrongTypedManifestValueIsCutInTheMessage) {
  write_png_stack();
  write("manifest.json", R"({"frames": [{}, {"gain": ")" + std::string(5'000'000, 'x') + R"("}, {}, {}]})");
  const std::string message = load_error();
  EXPECT_THAT(message, HasSubstr("frames[1].gain: expected a number, got \"xxxx"));
  EXPECT_THAT(message, HasSubstr("..."));
  EXPECT_LT(message.size(), 400u);
}

TEST_F(HostHostileStack, ControlCharactersInListedNamesAreEscaped) {
  write_png_stack();
  write("filenames.txt", "img_00.png\n../\x1b[2Jx.png\nimg_02.png\nimg_03.png\n");
  const std::string message = load_error();
  EXPECT_THAT(message, HasSubstr("'../\\x1b[2Jx.png' must name a file inside"));
  EXPECT_THAT(message, Not(HasSubstr("\x1b")));
}

}  // namespace
}  // namespace lightstage
