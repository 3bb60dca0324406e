#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/image_io.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>

namespace lightstage {
namespace {

using ::testing::HasSubstr;

using testing::error_of;

void write_raw(const std::filesystem::path& path, const std::string& header, const std::vector<float>& values,
               bool big_endian) {
  std::ofstream out(path, std::ios::binary);
  out << header;
  for (float v : values) {
    unsigned char bytes[4];
    std::memcpy(bytes, &v, 4);  // the test machine is little-endian (checked below)
    if (big_endian) std::swap(bytes[0], bytes[3]), std::swap(bytes[1], bytes[2]);
    out.write(reinterpret_cast<const char*>(bytes), 4);
  }
}

TEST(HostPfm, RoundTripsOneAndThreeChannels) {
  const auto dir = testing::scratch_dir();
  cv::Mat grey(5, 7, CV_32FC1), colour(4, 3, CV_32FC3);
  cv::randu(grey, -10, 10);
  cv::randu(colour, -1, 1);
  io::write_pfm(dir / "g.pfm", grey);
  io::write_pfm(dir / "c.pfm", colour);
  const cv::Mat g = io::read_pfm(dir / "g.pfm");
  const cv::Mat c = io::read_image(dir / "c.pfm");  // read_image dispatches on .pfm
  ASSERT_EQ(g.type(), CV_32FC1);
  ASSERT_EQ(c.type(), CV_32FC3);
  EXPECT_EQ(cv::norm(g, grey, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(c, colour, cv::NORM_INF), 0);
}

TEST(HostPfm, FileRowsAreBottomToTopAndChannelsRgb) {
  static_assert(std::endian::native == std::endian::little);
  const auto dir = testing::scratch_dir();
  // 2 wide, 2 high; the file's first row is the image's bottom row.
  write_raw(dir / "little.pfm", "Pf\n2 2\n-1.0\n", {1, 2, 3, 4}, false);
  write_raw(dir / "big.pfm", "Pf\n2 2\n1.0\n", {1, 2, 3, 4}, true);
  for (const char* name : {"little.pfm", "big.pfm"}) {
    const cv::Mat image = io::read_pfm(dir / name);
    ASSERT_EQ(image.type(), CV_32FC1) << name;
    EXPECT_EQ(image.at<float>(1, 0), 1) << name;  // bottom-left
    EXPECT_EQ(image.at<float>(1, 1), 2) << name;
    EXPECT_EQ(image.at<float>(0, 0), 3) << name;  // top-left
    EXPECT_EQ(image.at<float>(0, 1), 4) << name;
  }
  write_raw(dir / "rgb.pfm", "PF\n1 1\n-1\n", {0.25f, 0.5f, 0.75f}, false);
  const cv::Mat rgb = io::read_pfm(dir / "rgb.pfm");
  EXPECT_EQ(rgb.at<cv::Vec3f>(0, 0), cv::Vec3f(0.75f, 0.5f, 0.25f));  // BGR in memory

  // And what we write is laid out the same way.
  cv::Mat written = (cv::Mat_<float>(2, 1) << 10, 20);  // top 10, bottom 20
  io::write_pfm(dir / "ours.pfm", written);
  std::ifstream in(dir / "ours.pfm", std::ios::binary);
  const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string header = "Pf\n1 2\n-1\n";
  ASSERT_EQ(data.substr(0, header.size()), header);
  float first = 0;
  std::memcpy(&first, data.data() + header.size(), 4);
  EXPECT_EQ(first, 20);
}

TEST(HostPfm, MalformedFilesNameTheFile) {
  const auto dir = testing::scratch_dir();
  EXPECT_THAT(error_of([&] { io::read_pfm(dir / "none.pfm"); }), HasSubstr("none.pfm"));
  std::ofstream(dir / "magic.pfm") << "P6\n1 1\n255\n";
  EXPECT_THAT(error_of([&] { io::read_pfm(dir / "magic.pfm"); }), HasSubstr("magic.pfm: not a PFM"));
  write_raw(dir / "short.pfm", "Pf\n4 4\n-1\n", {1, 2, 3}, false);
  EXPECT_THAT(error_of([&] { io::read_pfm(dir / "short.pfm"); }), HasSubstr("short.pfm: truncated"));
  std::ofstream(dir / "size.pfm") << "Pf\nx 4\n-1\n";
  EXPECT_THAT(error_of([&] { io::read_pfm(dir / "size.pfm"); }), HasSubstr("size.pfm: malformed"));
  EXPECT_THAT(error_of([&] { io::write_pfm(dir / "w.pfm", cv::Mat(2, 2, CV_16UC1)); }), HasSubstr("w.pfm"));
}

}  // namespace
}  // namespace lightstage
