#include "lightstage/host/calibration/calibrate_lights.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/common/version.hpp"
#include "util/utc_time.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>

namespace lightstage::calibration {
namespace {

namespace fs = std::filesystem;

struct StackSpheres {
  CalibrationImages images;          // the index: its images are decoded as their highlights are sought
  cv::Mat median;                    // of every image whole
  cv::Rect region;                   // the pixels the highlights are sought in, around every sphere
  std::vector<std::size_t> spheres;  // indices into LightCalibration::spheres
};

CameraGeometry choose_camera(const LightCalibrationOptions& options, const CalibrationImages& images,
                             const std::optional<Rig>& rig) {
  if (options.camera) return *options.camera;
  if (images.camera) return *images.camera;
  if (rig) return CameraGeometry::from_rig(rig->camera, images.width(), images.height());
  return CameraGeometry::unknown(images.width(), images.height());
}

// The rig LED each image shows: by LED id when the stack knows it, else by order.
std::vector<const Led*> nominal_leds(const CalibrationImages& images, const Rig& rig) {
  std::vector<const Led*> leds(images.size(), nullptr);
  for (std::size_t i = 0; i < images.size(); ++i) {
    if (images.led_ids[i] >= 0) {
      for (const auto& led : rig.leds) {
        if (led.id == images.led_ids[i]) leds[i] = &led;
      }
    } else if (rig.leds.size() == images.size()) {
      leds[i] = &rig.leds[i];
    }
  }
  return leds;
}

// Triangulated positions are only as good as the highlights are bright and
// the rays are apart: say how well they are known, and whether the exposure
// left the highlights dim (their position noise falls as 1/√exposure).
void report_position_accuracy(const LightCalibration& cal) {
  if (cal.direction_method != "triangulated") return;
  double peak = 0;
  for (const auto& light : cal.lights)
    for (const auto& o : light.observations)
      if (o.highlight.usable()) peak = std::max(peak, o.highlight.peak);
  std::vector<double> sigmas;
  const CalibratedLight* worst = nullptr;
  for (const auto& light : cal.lights) {
    if (!light.position_sigma_mm) continue;
    sigmas.push_back(*light.position_sigma_mm);
    if (!worst || *light.position_sigma_mm > *worst->position_sigma_mm) worst = &light;
  }
  if (!worst) return;
  std::nth_element(sigmas.begin(), sigmas.begin() + static_cast<std::ptrdiff_t>(sigmas.size() / 2),
                   sigmas.end());
  logger("host")->info(
      "LED positions: standard deviation {:.2f} mm median, {:.2f} mm worst ({}), from highlights peaking at "
      "{:.0f}% of full scale",
      sigmas[sigmas.size() / 2], *worst->position_sigma_mm, worst->image, 100 * peak);
  if (peak < 0.25)
    logger("host")->warn(
        "the brightest highlight peaks at {:.0f}% of full scale: a longer exposure (peaks at 50-80%) lowers "
        "the "
        "LED position noise as 1/sqrt(exposure)",
        100 * peak);
}

// Where the intensity target is in its stack's images: the mask, else the median image's well-lit part
// (a flat target) or its one circle (a matte sphere).
TargetSurface intensity_target_surface(const CalibrationImages& target, const LightCalibration& cal,
                                       const LightCalibrationOptions& options) {
  if (options.intensity_target == IntensityTarget::kFlatTarget) {
    cv::Mat region = target.mask;
    if (region.empty()) {
      const cv::Mat median = calibration_views(target, options.threads).median;
      double high = 0;
      cv::minMaxLoc(median, nullptr, &high);
      cv::compare(median, 0.2 * high, region, cv::CMP_GT);
    }
    return TargetSurface::plane(region, cal.camera, cal.object_position_mm.z());
  }
  SphereDetectionOptions detection = options.detection;
  detection.expected = 1;
  const auto circles =
      target.mask.empty()
          ? detect_circles(calibration_views(target, options.threads).median, detection,
                           options.intensity_input.string() + " (median image)")
          : circles_from_mask(target.mask, detection, (options.intensity_input / "mask.png").string());
  const MirrorSphere sphere =
      locate_sphere(circles.front(), cal.camera, cal.object_position_mm.z(), options.sphere_radius_mm);
  return TargetSurface::sphere(sphere, cal.camera);
}

}  // namespace

std::vector<ImageCircle> find_sphere_circles(const CalibrationImages& images, const cv::Mat& median,
                                             const LightCalibrationOptions& options) {
  SphereDetectionOptions detection = options.detection;
  detection.expected = options.spheres_per_stack;
  std::vector<ImageCircle> circles;
  if (!options.given_circles.empty()) {
    circles = options.given_circles;
    for (auto& c : circles) c.source = "given";
  } else if (!images.mask.empty()) {
    circles = circles_from_mask(images.mask, detection, (images.folder / "mask.png").string());
  } else {
    circles =
        detect_circles(median, detection,
                       fmt::format("{} (median of its {} images)", images.folder.string(), images.size()));
  }
  // Left to right, then top to bottom: the same order in every stack.
  std::sort(circles.begin(), circles.end(), [](const ImageCircle& a, const ImageCircle& b) {
    return std::abs(a.centre_px.x() - b.centre_px.x()) > 1 ? a.centre_px.x() < b.centre_px.x()
                                                           : a.centre_px.y() < b.centre_px.y();
  });
  return circles;
}

void LightCalibrationOptions::check() const {
  if (inputs.empty()) fail("calibrate lights: at least one chrome-sphere stack (--input) is needed");
  if (spheres_per_stack < 1 || spheres_per_stack > 16)
    fail("calibrate lights: spheres per stack must be in 1..16, got {}", spheres_per_stack);
  if (!given_circles.empty() && static_cast<int>(given_circles.size()) != spheres_per_stack)
    fail("calibrate lights: {} sphere outline(s) given, but {} sphere(s) per stack expected",
         given_circles.size(), spheres_per_stack);
  for (const auto& c : given_circles) {
    if (!(c.radius_px > 0) || !c.centre_px.allFinite())
      fail(
          "calibrate lights: a given sphere outline needs a finite centre and a positive radius, got ({}, "
          "{}) r {}",
          c.centre_px.x(), c.centre_px.y(), c.radius_px);
  }
  if (!sphere_z_mm.empty() && sphere_z_mm.size() != 1 && sphere_z_mm.size() != inputs.size())
    fail("calibrate lights: {} sphere heights for {} stacks (give one for all, or one per stack)",
         sphere_z_mm.size(), inputs.size());
  if (!(sphere_radius_mm >= 0))
    fail("calibrate lights: sphere radius must not be negative, got {}", sphere_radius_mm);
  if (dome_radius_mm && !(*dome_radius_mm >= 0))
    fail("calibrate lights: dome radius must not be negative, got {}", *dome_radius_mm);
  if (camera) camera->check();
  if (threads < 0) fail("calibrate lights: threads must be 0 (automatic) or positive, got {}", threads);
  detection.check();
  highlight.check();
  intensity.check();
}

LightCalibrationRun calibrate_lights(const LightCalibrationOptions& options) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  std::optional<Rig> rig;
  if (!options.rig.empty()) rig = load_rig(options.rig);

  LightCalibrationRun run;
  LightCalibration& cal = run.calibration;
  cal.created = util::utc_timestamp();
  cal.software = std::string("lightstage ") + kVersion;
  if (rig) {
    cal.rig = options.rig.string();
    cal.object_position_mm = rig->object_position_mm;
  }
  cal.dome_radius_mm = options.dome_radius_mm;
  if (!cal.dome_radius_mm && rig) cal.dome_radius_mm = rig->dome_radius_mm;
  if (cal.dome_radius_mm && *cal.dome_radius_mm <= 0) cal.dome_radius_mm.reset();

  // Load every stack and place its spheres.
  std::vector<StackSpheres> stacks;
  for (std::size_t s = 0; s < options.inputs.size(); ++s) {
    // The median and brightest images first, a band of rows at a time; then only the spheres' pixels.
    StackSpheres stack{load_calibration_index(options.inputs[s]), {}, {}, {}};
    CalibrationImages& images = stack.images;
    if (s == 0) {
      cal.camera = choose_camera(options, images, rig);
    } else {
      const CalibrationImages& first = stacks.front().images;
      if (images.size() != first.size())
        fail("{}: {} images, but {} has {} (every stack must hold the same lights)", images.folder.string(),
             images.size(), first.folder.string(), first.size());
      if (images.width() != first.width() || images.height() != first.height())
        fail("{}: images are {}x{}, but {} has {}x{}", images.folder.string(), images.width(),
             images.height(), first.folder.string(), first.width(), first.height());
      for (std::size_t i = 0; i < images.size(); ++i) {
        if (images.led_ids[i] >= 0 && first.led_ids[i] >= 0 && images.led_ids[i] != first.led_ids[i])
          fail("{}: image {} shows LED {}, but image {} of {} shows LED {}", images.folder.string(),
               images.filenames[i], images.led_ids[i], first.filenames[i], first.folder.string(),
               first.led_ids[i]);
      }
    }
    const double z = options.sphere_z_mm.empty()       ? cal.object_position_mm.z()
                     : options.sphere_z_mm.size() == 1 ? options.sphere_z_mm.front()
                                                       : options.sphere_z_mm[s];
    CalibrationViews views = calibration_views(images, options.threads);
    stack.median = std::move(views.median);
    cv::Rect region;
    for (const auto& circle : find_sphere_circles(images, stack.median, options)) {
      region |= highlight_region(circle, images.image_size);
      stack.spheres.push_back(cal.spheres.size());
      cal.spheres.push_back({images.folder, locate_sphere(circle, cal.camera, z, options.sphere_radius_mm)});
      logger("host")->info(
          "{}: sphere at ({:.2f}, {:.2f}) px, radius {:.2f} px (from the {}, edge RMS {:.3f} px)",
          images.folder.string(), circle.centre_px.x(), circle.centre_px.y(), circle.radius_px, circle.source,
          circle.rms_px);
    }
    if (region.empty())
      fail("{}: no sphere lies inside the {}x{} images", images.folder.string(), images.width(),
           images.height());
    stack.region = region;
    run.sphere_views.push_back(std::move(views.maximum));
    stacks.push_back(std::move(stack));
  }

  // Highlights: every image of every stack, on every sphere in it.
  const CalibrationImages& first = stacks.front().images;
  const std::size_t lights = first.size();
  cal.lights.resize(lights);
  for (std::size_t i = 0; i < lights; ++i) {
    cal.lights[i].image = first.filenames[i];
    cal.lights[i].led_id = first.led_ids[i];
  }
  for (const auto& stack : stacks) {
    const cv::Mat background = stack.median(stack.region);
    const Vec2 origin(stack.region.x, stack.region.y);
    std::vector<ImageCircle> circles;  // each sphere's outline in the region's pixels
    for (const std::size_t sphere : stack.spheres) {
      circles.push_back(cal.spheres[sphere].sphere.circle);
      circles.back().centre_px -= origin;
    }
    // found[k][i]: the stack's sphere k in image i. Each image is decoded once, around the spheres only.
    std::vector<std::vector<SphereObservation>> found(stack.spheres.size(),
                                                      std::vector<SphereObservation>(lights));
    for_each_calibration_image(
        stack.images, stack.region, options.threads,
        [&](std::size_t i, const cv::Mat& grey, const cv::Mat& saturated) {
          for (std::size_t k = 0; k < stack.spheres.size(); ++k) {
            SphereObservation& o = found[k][i];
            o.sphere = stack.spheres[k];
            o.highlight = find_highlight(grey, background, saturated, circles[k], options.highlight);
            o.highlight.centre_px += origin;
            if (o.highlight.usable())
              o.reflection = reflect_at(cal.spheres[o.sphere].sphere, cal.camera, o.highlight.centre_px);
          }
        });
    for (std::size_t k = 0; k < stack.spheres.size(); ++k) {
      for (std::size_t i = 0; i < lights; ++i) {
        const Highlight& h = found[k][i].highlight;
        if (h.status != HighlightStatus::kFound) {
          cal.problems.push_back(fmt::format("{}: sphere {}: {}: {}",
                                             (stack.images.folder / stack.images.filenames[i]).string(),
                                             stack.spheres[k], status_name(h.status), h.note));
        }
        cal.lights[i].observations.push_back(std::move(found[k][i]));
      }
    }
  }

  // Directions (and positions) from the observations.
  const bool metric = cal.camera.metric;
  const bool several_positions = cal.spheres.size() >= 2 && metric;
  cal.direction_method = several_positions                ? "triangulated"
                         : (cal.dome_radius_mm && metric) ? "dome-radius"
                                                          : "mirror";
  std::vector<std::string> unmeasured;
  for (std::size_t i = 0; i < lights; ++i) {
    CalibratedLight& light = cal.lights[i];
    std::vector<Ray> rays;
    std::vector<HighlightObservation> highlights;
    Vec3 mirror_sum = Vec3::Zero();
    for (const auto& o : light.observations) {
      if (!o.reflection) continue;
      rays.push_back({o.reflection->point_mm, o.reflection->direction});
      highlights.push_back({cal.spheres[o.sphere].sphere, o.highlight.centre_px, o.highlight.covariance_px});
      mirror_sum += o.reflection->direction;
    }
    if (rays.empty()) {
      unmeasured.push_back(light.image);
      continue;
    }
    light.measured = true;
    light.direction = mirror_sum.normalized();
    if (several_positions && rays.size() >= 2) {
      if (const auto t = triangulate(rays)) {
        light.position_mm = t->position_mm;
        light.position_residual_mm = t->rms_mm;
        // The rays' nearest point treats every ray alike; the highlights'
        // own noise (and how it tilts each ray) decides the best position.
        if (const auto fit = refine_led_position(highlights, cal.camera, t->position_mm)) {
          light.position_mm = fit->position_mm;
          light.position_sigma_mm = fit->sigma_mm;
          light.reprojection_rms_px = fit->rms_px;
          double sum = 0;
          for (const auto& ray : rays) {
            const Vec3 offset = fit->position_mm - ray.origin;
            sum += (offset - offset.dot(ray.direction) * ray.direction).squaredNorm();
          }
          light.position_residual_mm = std::sqrt(sum / static_cast<double>(rays.size()));
        }
      }
    }
    if (!light.position_mm && cal.dome_radius_mm && metric) {
      // One ray (or parallel rays): where it meets the dome, centred on the dome frame's origin.
      Vec3 sum = Vec3::Zero();
      int hits = 0;
      for (const auto& ray : rays) {
        if (const auto p = intersect_dome(ray, Vec3::Zero(), *cal.dome_radius_mm)) {
          sum += *p;
          ++hits;
        }
      }
      if (hits > 0) light.position_mm = sum / hits;
    }
    if (light.position_mm) light.direction = (*light.position_mm - cal.object_position_mm).normalized();
  }
  report_position_accuracy(cal);
  if (!unmeasured.empty() && !options.allow_missing) {
    std::string details;
    for (const auto& p : cal.problems) details += "\n  " + p;
    fail(
        "calibrate lights: no usable highlight for {} of {} lights ({}); fix the captures or pass "
        "--allow-missing:{}",
        unmeasured.size(), lights, fmt::join(unmeasured, ", "), details);
  }

  // Nominal layout: per-light nominal positions, and the rigid fit as a sanity check.
  if (rig) {
    const auto leds = nominal_leds(first, *rig);
    std::vector<Vec3> nominal, measured;
    for (std::size_t i = 0; i < lights; ++i) {
      if (!leds[i]) continue;
      cal.lights[i].nominal_position_mm = leds[i]->position_mm;
      if (cal.lights[i].led_id < 0) cal.lights[i].led_id = leds[i]->id;
      if (cal.lights[i].position_mm) {
        nominal.push_back(leds[i]->position_mm);
        measured.push_back(*cal.lights[i].position_mm);
      }
    }
    if (nominal.size() >= 3) cal.nominal_fit = fit_to_nominal(nominal, measured);
  }

  // Intensities from a matte target under the same lights.
  if (!options.intensity_input.empty()) {
    const CalibrationImages target = load_calibration_index(options.intensity_input);
    if (target.size() != lights)
      fail("{}: {} images, but the chrome-sphere stack {} has {} (the same lights are needed)",
           options.intensity_input.string(), target.size(), first.folder.string(), lights);
    if (target.width() != cal.camera.width || target.height() != cal.camera.height)
      fail(
          "{}: images are {}x{}, but the chrome-sphere stack {} was taken at {}x{} (the same camera is "
          "needed)",
          options.intensity_input.string(), target.width(), target.height(), first.folder.string(),
          cal.camera.width, cal.camera.height);
    const bool flat = options.intensity_target == IntensityTarget::kFlatTarget;
    const TargetSurface surface = intensity_target_surface(target, cal, options);
    const IntensityResult fit =
        fit_intensities(target, surface, LightGeometry::of(cal), flat, options.intensity, options.threads);
    for (std::size_t i = 0; i < lights; ++i) {
      if (!cal.lights[i].measured) continue;
      cal.lights[i].intensity = fit.relative[i];
      cal.lights[i].intensity_residual = fit.residual[i];
    }
    cal.intensity_source = {{"stack", options.intensity_input.string()},
                            {"target", intensity_target_name(options.intensity_target)},
                            {"near_lights", cal.has_positions()},
                            {"pixels", fit.target_pixels}};
    run.flat_field = fit.flat_field;
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

}  // namespace lightstage::calibration
