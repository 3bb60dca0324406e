#pragma once
// Renders shading images of a scene: for every pixel the radiance reaching
// the camera at unit sensor scale,
//     shading = Σ_leds I · E(x) · material.shading(x, n, l(x), v) · visible(x, l)
//             + Σ_leds I · led_radiance · reflectance · coverage     (mirrors)
// with l(x) and E(x) from the light model: near (l(x) toward the LED, E =
// |P - o|² / |P - x|², i.e. 1/d² normalised to 1 at the object centre o) or
// distant (l = direction o → P, E = 1). Cast shadows come from
// Shape::occluded. A mirror shows each LED as a disk of led_radius_mm; pixels
// near a reflected LED are
// resolved by adaptive supersampling (16² to 64² per pixel) and then spread
// by the lens blur (Scene::highlight_blur_px, a Gaussian PSF integrated over
// pixels), so even a highlight smaller than a pixel has an intensity
// centroid accurate to a small fraction of a pixel. Diffuse shading is not
// blurred (it stays exact for tests and solvers).
//
// A scene whose material has a colour renders the diffuse and the specular
// parts apart (render_parts); colour channel c is then
//     diffuse · tint_c(x) + specular
// (render_colour), so highlights and mirrors stay white. render() is the grey
// rendering either way (the tint's BT.601 grey is 1), at the grey cost.

#include "lightstage/common/image_stack.hpp"
#include "lightstage/sim/scene.hpp"

#include <opencv2/core.hpp>

#include <vector>

namespace lightstage::sim {

enum class LightModel { kNear, kDistant };

struct LightSource {
  Vec3 position_mm = Vec3(0, 0, 1000);  // dome frame
  double intensity = 1.0;               // relative intensity × fraction of the exposure it was on
};

class Renderer {
 public:
  Renderer(const Scene& scene, const Camera& camera, const Vec3& object_position_mm, LightModel model,
           int threads = 0);

  // CV_64FC1 shading image lit by `lights` (see the formula above).
  cv::Mat render(const std::vector<LightSource>& lights) const;
  // The same split in two CV_64FC1 images: *diffuse, the kd · albedo ·
  // diffuse lobe part (the part a colour tints), and *specular, the rest
  // (specular lobes, mirror highlights, the reflected environment). Their sum
  // is render(lights) up to rounding.
  void render_parts(const std::vector<LightSource>& lights, cv::Mat* diffuse, cv::Mat* specular) const;
  // CV_64FC3 shading in OpenCV's BGR order: diffuse · tint + specular per
  // channel. A scene without a colour gives three equal channels.
  cv::Mat render_colour(const std::vector<LightSource>& lights) const;
  // True when the scene's material has a colour (World::frame then makes CV_16UC3 frames).
  bool has_colour() const { return !tint_.empty(); }

  const cv::Mat& mask() const { return mask_; }
  const GroundTruth& ground_truth() const { return truth_; }
  // Diffuse albedo of the surface seen at each pixel (CV_32FC1, 0 off the object).
  cv::Mat albedo_map() const;
  // The colour tint of the surface seen at each pixel (CV_32FC3, BGR order,
  // BT.601 grey 1 on the object, 0 off it); (1, 1, 1) on the object when the
  // scene has no colour.
  cv::Mat tint_map() const;
  const Camera& camera() const { return camera_; }

  // Light direction and irradiance factor at object-frame point x for an LED at
  // object-frame position p; *distance = how far a shadow ray must go.
  void light_at(const Vec3& p, const Vec3& x, Vec3* dir, double* irradiance, double* distance) const;

 private:
  struct Pixel {
    bool hit = false;
    Vec3 point, normal, view;
    double albedo = 0;
    Vec3 reflect;       // mirror direction of the view
    double spread = 0;  // max angle between `reflect` here and at the pixel's corners
  };
  struct Splat {
    double u, v;    // centroid of the pixel's part of a highlight, pixels
    double weight;  // the fraction of the pixel it covers
  };
  Splat mirror_coverage(int row, int col, const Pixel& px, const Vec3& led) const;
  void add_mirror(const Vec3& led, double scale, cv::Mat& out) const;
  // Renders into *out; with `specular` set, the non-diffuse part goes there instead.
  void shade(const std::vector<LightSource>& lights, cv::Mat* out, cv::Mat* specular) const;
  std::optional<Hit> trace(double u, double v, Vec3* view) const;
  // Fraction of each pixel the object covers (8×8 samples where the
  // silhouette crosses the pixel), for Scene::environment_radiance.
  cv::Mat silhouette_coverage() const;

  Scene scene_;
  Camera camera_;
  Vec3 object_position_;
  LightModel model_;
  int threads_;
  std::vector<Pixel> pixels_;
  cv::Mat mask_;
  cv::Mat coverage_;  // CV_64FC1, only when a mirror reflects an environment
  cv::Mat tint_;      // CV_64FC3 (BGR), only when the material has a colour
  GroundTruth truth_;
};

}  // namespace lightstage::sim
