// RTI exchange: PTM and HSH fits, and PTM / HSH files written and read back.
#include "lightstage/host/io/rti_files.hpp"
#include "lightstage/host/reflectance/rti_basis.hpp"
#include "lightstage/testing/errors.hpp"
#include "synthetic.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace lightstage {
namespace {

using testing::error_of;

Eigen::MatrixX3d lights(int count, unsigned seed) { return testing::uniform_z_lights(count, seed, 0.2); }

// A w × h object: per pixel a Lambertian normal with a glossy lobe, one
// chromaticity per pixel (what PTM LRGB can hold exactly).
struct Scene {
  int width = 7, height = 5;
  std::vector<Vec3> normals;
  std::vector<Vec3> colours;
  float value(int pixel, int channel, const Vec3& light) const {
    const Vec3 l = light.normalized(), n = normals[pixel];
    const Vec3 h = (l + Vec3::UnitZ()).normalized();
    const double shade = std::max(n.dot(l), 0.0) + 0.3 * std::pow(std::max(n.dot(h), 0.0), 8);
    return static_cast<float>(colours[pixel][channel] * shade);
  }
};

Scene make_scene() {
  Scene s;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.5, 0.5), c(0.2, 0.9);
  for (int i = 0; i < s.width * s.height; ++i) {
    s.normals.push_back(Vec3(u(rng), u(rng), 1).normalized());
    s.colours.emplace_back(c(rng), c(rng), c(rng));
  }
  return s;
}

io::RtiImage fit(const Scene& s, RtiBasis basis, const Eigen::MatrixX3d& l) {
  io::RtiImage image;
  image.basis = basis;
  image.width = s.width;
  image.height = s.height;
  const int n = s.width * s.height;
  for (int c = 0; c < 3; ++c) {
    Eigen::MatrixXf values(n, l.rows());
    for (int p = 0; p < n; ++p)
      for (int j = 0; j < l.rows(); ++j) values(p, j) = s.value(p, c, l.row(j).transpose());
    image.channels[c] = fit_rti(basis, values, l);
  }
  return image;
}

// RMS over pixels and channels of (b − a) relative to the RMS of a, under `light`.
double relative_rms(const io::RtiImage& a, const io::RtiImage& b, const Vec3& light) {
  double num = 0, den = 0;
  for (int c = 0; c < 3; ++c) {
    const Eigen::VectorXf va = evaluate_rti(a.basis, a.channels[c], light);
    const Eigen::VectorXf vb = evaluate_rti(b.basis, b.channels[c], light);
    num += (vb - va).squaredNorm();
    den += va.squaredNorm();
  }
  return std::sqrt(num / den);
}

TEST(RtiBasis, PtmFitsAPolynomialExactly) {
  const Eigen::MatrixX3d l = lights(20, 1);
  Eigen::MatrixXf values(1, 20);
  const double a[6] = {0.3, -0.2, 0.1, 0.4, -0.1, 0.5};
  for (int j = 0; j < 20; ++j) {
    const double u = l(j, 0), v = l(j, 1);
    values(0, j) =
        static_cast<float>(a[0] * u * u + a[1] * v * v + a[2] * u * v + a[3] * u + a[4] * v + a[5]);
  }
  const Eigen::MatrixXf c = fit_rti(RtiBasis::ptm, values, l);
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(c(0, k), a[k], 1e-5) << k;
}

TEST(RtiBasis, HshFitsItsOwnBasisAndBeatsLowerOrder) {
  const Scene s = make_scene();
  const Eigen::MatrixX3d l = lights(40, 2), probe = lights(10, 9);
  double err2 = 0, err3 = 0, den = 0;
  const auto h2 = fit(s, RtiBasis::hsh2, l), h3 = fit(s, RtiBasis::hsh3, l);
  for (int j = 0; j < probe.rows(); ++j) {
    const Vec3 light = probe.row(j).transpose();
    const Eigen::VectorXf v2 = evaluate_rti(RtiBasis::hsh2, h2.channels[1], light);
    const Eigen::VectorXf v3 = evaluate_rti(RtiBasis::hsh3, h3.channels[1], light);
    for (int p = 0; p < s.width * s.height; ++p) {
      const double truth = s.value(p, 1, light);
      err2 += std::pow(v2(p) - truth, 2);
      err3 += std::pow(v3(p) - truth, 2);
      den += truth * truth;
    }
  }
  EXPECT_LT(std::sqrt(err3 / den), std::sqrt(err2 / den));
  EXPECT_LT(std::sqrt(err3 / den), 0.1);
}

TEST(RtiBasis, TooFewLightsIsAnError) {
  EXPECT_NE(error_of([] { fit_rti(RtiBasis::hsh3, Eigen::MatrixXf(1, 5), lights(5, 1)); }).find("at least 9"),
            std::string::npos);
}

TEST(RtiFiles, PtmRoundTripsAndRelightsWithinOnePercent) {
  const Scene s = make_scene();
  const auto fitted = fit(s, RtiBasis::ptm, lights(30, 4));
  for (const auto format : {io::PtmFormat::lrgb, io::PtmFormat::rgb}) {
    const std::string bytes = io::format_ptm(fitted, format);
    const io::RtiImage back = io::parse_ptm(bytes, "test.ptm");
    ASSERT_EQ(back.width, s.width);
    ASSERT_EQ(back.height, s.height);
    const Eigen::MatrixX3d probe = lights(12, 5);
    for (int j = 0; j < probe.rows(); ++j)
      EXPECT_LT(relative_rms(fitted, back, probe.row(j).transpose()), 0.01) << (format == io::PtmFormat::rgb);
  }
}

TEST(RtiFiles, PtmStoresRowsBottomToTop) {
  io::RtiImage image;
  image.width = 1;
  image.height = 2;
  for (auto& c : image.channels) {
    c = Eigen::MatrixXf::Zero(2, 6);
    c(0, 5) = 1;  // top pixel bright, bottom dark
  }
  const std::string bytes = io::format_ptm(image, io::PtmFormat::rgb);
  const std::size_t data = bytes.size() - 3 * 2 * 6;
  // First stored texel is the bottom row: its a5 byte equals the bias of a5.
  const io::RtiImage back = io::parse_ptm(bytes, "t.ptm");
  EXPECT_NEAR(back.channels[0](0, 5), 1, 1e-2);
  EXPECT_NEAR(back.channels[0](1, 5), 0, 1e-2);
  EXPECT_LT(static_cast<unsigned char>(bytes[data + 5]), static_cast<unsigned char>(bytes[data + 6 + 5]));
}

// relight reads an .rti's first row as the image's top (LRti::loadHSH flips
// it, then writes planes bottom-up) and writes it so (saveUniversal), unlike .ptm.
TEST(RtiFiles, HshStoresRowsTopToBottom) {
  io::RtiImage image;
  image.basis = RtiBasis::hsh2;
  image.width = 1;
  image.height = 2;
  for (auto& c : image.channels) {
    c = Eigen::MatrixXf::Zero(2, 4);
    c(0, 0) = 1;  // top pixel bright, bottom dark
  }
  const std::string bytes = io::format_hsh(image);
  const std::size_t data = bytes.size() - 2 * 3 * 4;
  EXPECT_EQ(static_cast<unsigned char>(bytes[data]), 255);        // first pixel, red, term 0: the top
  EXPECT_EQ(static_cast<unsigned char>(bytes[data + 3 * 4]), 0);  // second pixel: the bottom
  const io::RtiImage back = io::parse_hsh(bytes, "t.rti");
  EXPECT_NEAR(back.channels[0](0, 0), 1, 1e-2);
  EXPECT_NEAR(back.channels[0](1, 0), 0, 1e-2);
}

TEST(RtiFiles, HshRoundTripsAndRelightsWithinOnePercent) {
  const Scene s = make_scene();
  for (const auto basis : {RtiBasis::hsh2, RtiBasis::hsh3}) {
    const auto fitted = fit(s, basis, lights(40, 6));
    const io::RtiImage back = io::parse_hsh(io::format_hsh(fitted), "test.rti");
    ASSERT_EQ(back.basis, basis);
    const Eigen::MatrixX3d probe = lights(12, 7);
    for (int j = 0; j < probe.rows(); ++j)
      EXPECT_LT(relative_rms(fitted, back, probe.row(j).transpose()), 0.01) << rti_basis_name(basis);
  }
}

TEST(RtiFiles, BadFilesNameFileAndField) {
  const Scene s = make_scene();
  const std::string ptm = io::format_ptm(fit(s, RtiBasis::ptm, lights(30, 4)), io::PtmFormat::lrgb);
  EXPECT_EQ(error_of([&] { io::parse_ptm(ptm.substr(0, ptm.size() - 1), "a.ptm"); }),
            "a.ptm: rgb: 105 bytes expected, 104 left");
  EXPECT_EQ(error_of([&] { io::parse_ptm("PTM_1.2\nPTM_FORMAT_LUM\n", "b.ptm"); }),
            "b.ptm: format: 'PTM_FORMAT_LUM' is not PTM_FORMAT_LRGB or PTM_FORMAT_RGB");
  EXPECT_EQ(error_of([&] { io::parse_ptm("PTM_1.2\nPTM_FORMAT_RGB\n0 3\n", "c.ptm"); }),
            "c.ptm: size: 0x3 is outside 1..16384");
  EXPECT_EQ(error_of([&] { io::parse_hsh("#HSH1.2\n3\n2 2 3\n5 2 1\n", "d.rti"); }),
            "d.rti: terms: 5 is not 4 or 9");
  const std::string hsh = io::format_hsh(fit(s, RtiBasis::hsh2, lights(30, 4)));
  EXPECT_EQ(error_of([&] { io::parse_hsh(hsh.substr(0, hsh.size() - 2), "e.rti"); }),
            "e.rti: coefficients: 420 bytes expected, 418 left");
}

}  // namespace
}  // namespace lightstage
