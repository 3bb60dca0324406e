#include "shape_prior_args.hpp"

namespace lightstage::cli {

void add_shape_prior_flags(CLI::App& sub, pipeline::ShapePriorSettings& args) {
  sub.add_option("--prior", args.prior,
                 "shape-prior: coarse depth (16-bit PNG, PFM, single-channel EXR, or a PLY mesh in the "
                 "camera frame; docs/surfaces.md)");
  sub.add_option(
      "--intrinsics", args.intrinsics,
      "shape-prior: 3x3 intrinsics (K.txt) of a perspective camera; without it the camera is orthographic");
  sub.add_option("--pixel-mm", args.pixel_mm,
                 "shape-prior: orthographic pixel size in the prior's depth unit")
      ->capture_default_str();
  sub.add_option("--sh", args.options.sh_dimension, "shape-prior: lighting dimension k, 9 or 16")
      ->check(CLI::IsMember({9, 16}))
      ->capture_default_str();
  sub.add_option("--prior-radius", args.prior_radius,
                 "shape-prior: plane-PCA radius d for the prior's normals, in its depth unit (0 = 3 pixels)")
      ->capture_default_str();
  sub.add_option("--prior-png-scale", args.png_scale, "shape-prior: depth unit per DN of a 16-bit PNG prior")
      ->capture_default_str();
  sub.add_option("--smoothing", args.options.smoothing_sigma,
                 "shape-prior: Gaussian sigma (pixels) of Eq. 4.6")
      ->capture_default_str();
  sub.add_flag("!--no-refine", args.options.refine, "shape-prior: skip the Nelder-Mead refinement (Eq. 4.7)");
  sub.add_flag(
      "!--no-keep-prior", args.options.keep_prior,
      "shape-prior: use the fit's normal everywhere, even where the prior's explains the images as well");
  sub.add_option(
         "--keep-prior-margin", args.options.keep_prior_margin,
         "shape-prior: the prior's normal is kept unless the fit's lowers the pixel's photometric cost by "
         "more than this many times the fit's median cost")
      ->capture_default_str();
}

}  // namespace lightstage::cli
