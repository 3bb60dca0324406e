#pragma once
// Reflectance lobes for the simulated world. Convention (used everywhere in
// sim/): a lobe returns the *normalised* BRDF, π times the physical one, so
// that the rendered value at unit irradiance is
//     value = lobe.eval(n, l, v) * max(n·l, 0)
// and a white Lambertian surface facing the light renders exactly 1.0.
// All vectors are unit, in the camera frame, pointing away from the surface.

#include "lightstage/common/geometry.hpp"

#include <cstdint>
#include <map>
#include <memory>
#include <string>

namespace lightstage::sim {

class Brdf {
 public:
  virtual ~Brdf() = default;
  // π·f_r(n, l, v); never negative. Zero when l or v is below the surface.
  virtual double eval(const Vec3& n, const Vec3& l, const Vec3& v) const = 0;
  // The preset string that recreates this lobe ("ward:alpha=0.2").
  virtual std::string describe() const = 0;
  // A perfect mirror has no finite BRDF; the renderer reflects the LEDs instead.
  virtual bool is_mirror() const { return false; }
};

// ρ = 1.
class Lambert final : public Brdf {
 public:
  double eval(const Vec3& n, const Vec3& l, const Vec3& v) const override;
  std::string describe() const override { return "lambert"; }
};

// Qualitative Oren–Nayar (1994) with surface roughness sigma (radians);
// sigma = 0 is Lambert.
class OrenNayar final : public Brdf {
 public:
  explicit OrenNayar(double sigma);
  double eval(const Vec3& n, const Vec3& l, const Vec3& v) const override;
  std::string describe() const override;

 private:
  double sigma_, a_, b_;
};

// Wolff (1994) diffuse reflection from a smooth dielectric with refractive
// index eta: light is refracted in, scattered, and refracted out, so
// ρ ∝ (1 − F(θ_i)) · (1 − F(θ_r)) (F: unpolarised Fresnel reflectance at η;
// leaving at θ_t inside transmits as entering at θ_r outside). Scaled to 1
// at normal incidence and exit. Unlike Lambert it darkens at grazing
// incidence (η = 1.5: 0.95 of the normal-incidence value at 60°, 0.86 at
// 70°, 0.64 at 80°), as real plastics,
// paints and glazes do (the DiLiGenT ball: 0.94 at 60–70°, 0.87 at 70–80°).
class WolffDiffuse final : public Brdf {
 public:
  explicit WolffDiffuse(double eta);
  double eval(const Vec3& n, const Vec3& l, const Vec3& v) const override;
  std::string describe() const override;

 private:
  double eta_, scale_;
};

// Energy-normalised Blinn–Phong: (s+8)/8 · (n·h)^s. Reciprocal, monotonic in n·h.
class BlinnPhong final : public Brdf {
 public:
  explicit BlinnPhong(double shininess);
  double eval(const Vec3& n, const Vec3& l, const Vec3& v) const override;
  std::string describe() const override;

 private:
  double shininess_;
};

// Cook–Torrance (1982) specular lobe: Beckmann D (roughness m), Schlick
// Fresnel (normal-incidence reflectance f0), Torrance–Sparrow G;
// π · D F G / (4 (n·l)(n·v)).
class CookTorrance final : public Brdf {
 public:
  CookTorrance(double roughness, double f0);
  double eval(const Vec3& n, const Vec3& l, const Vec3& v) const override;
  std::string describe() const override;

 private:
  double m_, f0_;
};

// Isotropic Ward (1992): exp(-tan²δ/α²) / (4 α² sqrt((n·l)(n·v))), δ = angle(n, h).
class Ward final : public Brdf {
 public:
  explicit Ward(double alpha);
  double eval(const Vec3& n, const Vec3& l, const Vec3& v) const override;
  std::string describe() const override;

 private:
  double alpha_;
};

// The dissertation's Fig. 2.8(b): k1 ρ(n·v) + k2 ρ(n·k), k = normalize(v + 2l),
// ρ(x) = max(x, 0). A fabric-like BRDF whose lobes are not centred at h
// (deliberately not reciprocal).
class FabricTwoLobe final : public Brdf {
 public:
  FabricTwoLobe(double k1, double k2);
  double eval(const Vec3& n, const Vec3& l, const Vec3& v) const override;
  std::string describe() const override;

 private:
  double k1_, k2_;
};

// The dissertation's Fig. 2.8(c): k1 ρ(n·h) + k2 ρ(n·k), ρ(x) = max(x, 0),
// k a pseudo-random unit direction per (normal, light) pair: a hash of the
// bits of n and l, so a pixel under a light always sees the same k and
// rendering stays deterministic.
class RandomTwoLobe final : public Brdf {
 public:
  RandomTwoLobe(double k1, double k2, std::uint64_t seed);
  double eval(const Vec3& n, const Vec3& l, const Vec3& v) const override;
  std::string describe() const override;

 private:
  double k1_, k2_;
  std::uint64_t seed_;
};

// A chrome mirror: eval is 0; the renderer reflects the LED disks.
class Mirror final : public Brdf {
 public:
  double eval(const Vec3&, const Vec3&, const Vec3&) const override { return 0; }
  std::string describe() const override { return "chrome"; }
  bool is_mirror() const override { return true; }
};

// "name:key=value,key=value" split into its name and parameters. Throws
// InputError (naming `what` and the text) on malformed input.
struct PresetString {
  std::string name;
  std::map<std::string, double> params;
};
PresetString parse_preset_string(const std::string& text, const std::string& what);

// Mixes two directions' hash into a value in [0, 1); exposed for tests.
double hash_unit(std::uint64_t a, std::uint64_t b);

}  // namespace lightstage::sim
