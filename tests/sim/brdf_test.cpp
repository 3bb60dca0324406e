#include "lightstage/sim/brdf.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/sim/material.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <vector>

namespace lightstage::sim {
namespace {

Vec3 random_upper(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Vec3 v(g(rng), g(rng), std::abs(g(rng)) + 0.05);
  return v.normalized();
}

std::vector<std::shared_ptr<Brdf>> reciprocal_lobes() {
  return {std::make_shared<Lambert>(),      std::make_shared<OrenNayar>(0.4),
          std::make_shared<BlinnPhong>(30), std::make_shared<CookTorrance>(0.3, 0.5),
          std::make_shared<Ward>(0.2),      std::make_shared<WolffDiffuse>(1.5)};
}

TEST(SimBrdf, ReciprocalAndNonNegative) {
  std::mt19937_64 rng(7);
  for (const auto& lobe : reciprocal_lobes()) {
    for (int i = 0; i < 2000; ++i) {
      const Vec3 n = random_upper(rng), l = random_upper(rng), v = random_upper(rng);
      const double a = lobe->eval(n, l, v);
      const double b = lobe->eval(n, v, l);
      ASSERT_GE(a, 0.0) << lobe->describe();
      ASSERT_NEAR(a, b, 1e-9 * std::max(1.0, a)) << lobe->describe();
    }
  }
}

TEST(SimBrdf, ZeroBelowTheSurface) {
  const Vec3 n = Vec3::UnitZ(), below = Vec3(0.3, 0, -1).normalized(), up = Vec3(0.2, 0.1, 1).normalized();
  for (const auto& lobe : reciprocal_lobes()) {
    EXPECT_EQ(lobe->eval(n, below, up), 0.0) << lobe->describe();
    EXPECT_EQ(lobe->eval(n, up, below), 0.0) << lobe->describe();
  }
}

// The single-lobe models the monotonic solver assumes decrease as n moves away
// from h with l·h fixed: n(t) = cos t·h + sin t·w, w ⊥ h and ⊥ (l - v), so
// n·l = n·v throughout.
TEST(SimBrdf, MonotonicInNDotHAtFixedLDotH) {
  const std::vector<std::shared_ptr<Brdf>> lobes = {std::make_shared<BlinnPhong>(50),
                                                    std::make_shared<CookTorrance>(0.3, 0.5),
                                                    std::make_shared<Ward>(0.2)};
  std::mt19937_64 rng(3);
  for (const auto& lobe : lobes) {
    for (int trial = 0; trial < 50; ++trial) {
      const Vec3 l = random_upper(rng), v = random_upper(rng);
      if ((l - v).norm() < 0.1) continue;
      const Vec3 h = (l + v).normalized();
      const Vec3 w = h.cross(l - v).normalized();
      double previous = std::numeric_limits<double>::infinity();
      for (int k = 0; k <= 40; ++k) {
        const double t = rad_from_deg(1.5 * k);
        const Vec3 n = std::cos(t) * h + std::sin(t) * w;
        if (n.dot(l) <= 0.05) break;
        const double value = lobe->eval(n, l, v);
        ASSERT_LE(value, previous * (1 + 1e-12)) << lobe->describe() << " at t=" << 1.5 * k;
        previous = value;
      }
    }
  }
}

TEST(SimBrdf, LambertFacingTheLightIsOne) {
  const Material m = parse_material("lambert");
  const Vec3 z = Vec3::UnitZ();
  EXPECT_DOUBLE_EQ(m.shading(0, 0, z, z, z), 1.0);
  const Vec3 l = Vec3(1, 0, 1).normalized();
  EXPECT_NEAR(m.shading(0, 0, z, l, z), std::sqrt(0.5), 1e-15);
  const Material grey = parse_material("lambert:albedo=0.25");
  EXPECT_DOUBLE_EQ(grey.shading(0, 0, z, z, z), 0.25);
}

TEST(SimBrdf, OrenNayarWithZeroRoughnessIsLambert) {
  const OrenNayar on(0.0);
  std::mt19937_64 rng(1);
  for (int i = 0; i < 100; ++i) {
    const Vec3 n = random_upper(rng), l = random_upper(rng), v = random_upper(rng);
    if (n.dot(l) > 0 && n.dot(v) > 0) {
      EXPECT_NEAR(on.eval(n, l, v), 1.0, 1e-12);
    }
  }
}

// Fresnel transmission in and out: 1 at normal incidence and exit, darker at
// grazing incidence (values from the Fresnel equations at η = 1.5).
TEST(SimBrdf, WolffDiffuseDarkensAtGrazingIncidence) {
  const WolffDiffuse wolff(1.5);
  const Vec3 n = Vec3::UnitZ();
  auto at = [](double deg) { return Vec3(std::sin(rad_from_deg(deg)), 0, std::cos(rad_from_deg(deg))); };
  EXPECT_NEAR(wolff.eval(n, n, n), 1.0, 1e-12);
  EXPECT_NEAR(wolff.eval(n, at(60), n), 0.9488, 1e-4);
  EXPECT_NEAR(wolff.eval(n, at(80), n), 0.6378, 1e-4);
  EXPECT_NEAR(wolff.eval(n, at(60), at(80)), 0.9488 * 0.6378, 1e-4);
  EXPECT_THROW(WolffDiffuse(1.0), Error);
  const Material dielectric = parse_material("dielectric:eta=1.5,ks=0");
  EXPECT_NEAR(dielectric.shading(0, 0, n, at(80), n), 0.6378 * std::cos(rad_from_deg(80)), 1e-4);
}

TEST(SimBrdf, TwoLobeFamiliesFollowTheDissertation) {
  const FabricTwoLobe fabric(0.3, 0.7);
  const Vec3 n = Vec3(0.1, 0.2, 1).normalized(), l = Vec3(0.5, -0.2, 1).normalized(), v = Vec3::UnitZ();
  EXPECT_NEAR(fabric.eval(n, l, v), 0.3 * n.dot(v) + 0.7 * n.dot((v + 2 * l).normalized()), 1e-15);
  const RandomTwoLobe random(0.5, 0.5, 9);
  const double a = random.eval(n, l, v);
  EXPECT_EQ(a, random.eval(n, l, v));  // deterministic per (n, l)
  EXPECT_GE(a, 0.5 * n.dot((l + v).normalized()) - 1e-15);
  const Material ct = parse_material("two-lobe-ct:k1=0.2,k2=0.8");
  EXPECT_DOUBLE_EQ(ct.kd, 0.2);
  EXPECT_DOUBLE_EQ(ct.ks, 0.8);
}

TEST(SimBrdf, EveryPresetParses) {
  for (const auto& preset : material_presets()) {
    const Material m = parse_material(preset);
    EXPECT_FALSE(m.describe().dump().empty()) << preset;
  }
  EXPECT_TRUE(parse_material("chrome").is_mirror());
  EXPECT_FALSE(parse_material("ward:alpha=0.1").is_mirror());
}

TEST(SimBrdf, BadPresetsNameTheProblem) {
  auto message = [](const std::string& preset) {
    try {
      parse_material(preset);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("plastic").find("plastic"), std::string::npos);
  EXPECT_NE(message("ward:alhpa=0.2").find("alhpa"), std::string::npos);
  EXPECT_NE(message("ward:alpha=abc").find("alpha"), std::string::npos);
  EXPECT_NE(message("ward:alpha=-1").find("alpha"), std::string::npos);
  EXPECT_NE(message("blinn-phong:shininess").find("shininess"), std::string::npos);
}

}  // namespace
}  // namespace lightstage::sim
