// The `lightstage` Python module: the host pipeline in process, with numpy
// arrays in and out — load a stack, calibrate lights, solve with any method of
// the registry and its options, integrate a surface, measure angular error.
// Errors raise lightstage.InputError (a ValueError) naming the file, field or
// value, or lightstage.Error (a RuntimeError).
#include "lightstage/common/error.hpp"
#include "lightstage/common/version.hpp"
#include "lightstage/host/calibration/calibrate_lights.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/io/exr.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/surface/integration.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/pipeline/solve_methods.hpp"
#include "numpy_arrays.hpp"
#include "solve_options.hpp"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace py = pybind11;
namespace fs = std::filesystem;

namespace lightstage::python {
namespace {

py::dict stack_dict(const fs::path& path) {
  const ImageStack stack = io::load_stack(path);
  py::list images, filenames;
  Eigen::MatrixXd directions(static_cast<Eigen::Index>(stack.frames.size()), 3);
  Eigen::MatrixXd intensities(static_cast<Eigen::Index>(stack.frames.size()), 3);
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    const Frame& frame = stack.frames[i];
    images.append(image_to_numpy(frame.image));
    filenames.append(frame.filename);
    directions.row(static_cast<Eigen::Index>(i)) = frame.light_direction.transpose();
    intensities.row(static_cast<Eigen::Index>(i)) = frame.light_intensity.transpose();
  }
  py::dict out;
  out["path"] = path;
  out["images"] = images;
  out["filenames"] = filenames;
  out["light_directions"] = to_numpy(directions);
  out["light_intensities"] = to_numpy(intensities);
  out["mask"] = stack.mask.empty() ? py::object(py::none()) : py::object(mask_to_numpy(stack.mask));
  out["normals_gt"] = stack.ground_truth && !stack.ground_truth->normals.empty()
                          ? py::object(to_numpy(stack.ground_truth->normals))
                          : py::object(py::none());
  return out;
}

py::object optional_map(const cv::Mat& map) {
  return map.empty() ? py::object(py::none()) : py::object(to_numpy(map));
}

py::dict result_dict(const SolveResult& result, const std::optional<AngularErrorStats>& error) {
  py::dict out;
  out["normals"] = to_numpy(result.normals);
  out["albedo"] = to_numpy(result.albedo);
  out["residual"] = to_numpy(result.residual);
  out["solved"] = mask_to_numpy(result.solved);
  out["confidence"] = optional_map(result.confidence);
  out["coefficients"] = optional_map(result.coefficients);
  nlohmann::json summary = result.summary.to_json();
  summary["parameters"] = result.parameters;
  if (!result.reflectance.is_null()) summary["reflectance"] = result.reflectance;
  if (error) summary["error_vs_ground_truth"] = error->to_json();
  out["summary"] = py::module_::import("json").attr("loads")(summary.dump());
  return out;
}

py::dict solve(const fs::path& input, const std::string& method, const std::optional<fs::path>& calibration,
               bool distant_lights, const py::kwargs& options) {
  pipeline::SolveSettings settings;
  settings.method = method;
  apply_solve_options(settings, options);
  settings.resolve();
  pipeline::SolveCalibration light_calibration;
  if (calibration) light_calibration.file = *calibration;
  light_calibration.distant = distant_lights;
  SolveResult result;
  std::optional<AngularErrorStats> error;
  {
    py::gil_scoped_release unlocked;  // the solve is long and touches no Python object
    const pipeline::SolveInput prepared =
        pipeline::load_solve_input(input, settings.radiometry, light_calibration);
    result = pipeline::solve_with(prepared.observations, settings, prepared.shadow);
    if (prepared.ground_truth && !prepared.ground_truth->normals.empty())
      error = angular_error(result.normals, prepared.ground_truth->normals, prepared.observations.mask).stats;
  }
  return result_dict(result, error);
}

py::dict integrate(const py::array& normals_array, const std::optional<py::array>& mask_array,
                   double pixel_mm, const std::string& method, bool preserve_discontinuities) {
  const cv::Mat normals = float_mat(normals_array, 3, "normals");
  cv::Mat mask;
  if (mask_array) {
    mask = mask_mat(*mask_array, "mask");
    if (mask.size() != normals.size()) throw py::value_error("mask: must have the normals' height and width");
  } else {
    // Where the map holds a normal.
    mask = cv::Mat(normals.size(), CV_8UC1, cv::Scalar(0));
    for (int y = 0; y < normals.rows; ++y)
      for (int x = 0; x < normals.cols; ++x)
        if (cv::norm(normals.at<cv::Vec3f>(y, x)) > 0.5) mask.at<std::uint8_t>(y, x) = 255;
  }
  surface::IntegrationOptions options;
  options.method = surface::parse_integration_method(method);
  options.preserve_discontinuities = preserve_discontinuities;
  const surface::CameraModel camera = surface::CameraModel::orthographic(normals.size(), pixel_mm);
  surface::SurfaceResult surface;
  {
    py::gil_scoped_release unlocked;
    surface = surface::integrate_normals(normals, mask, camera, options);
  }
  py::dict out;
  out["depth"] = to_numpy(surface.depth);
  out["valid"] = mask_to_numpy(surface.valid);
  out["pixels"] = surface.stats.pixels;
  out["seconds"] = surface.stats.seconds;
  return out;
}

py::dict error_stats(const py::array& predicted, const py::array& truth,
                     const std::optional<py::array>& mask) {
  const cv::Mat p = float_mat(predicted, 3, "predicted");
  const cv::Mat t = float_mat(truth, 3, "truth");
  if (p.size() != t.size()) throw py::value_error("predicted and truth must have the same height and width");
  const cv::Mat m = mask ? mask_mat(*mask, "mask") : cv::Mat(p.size(), CV_8UC1, cv::Scalar(255));
  const AngularErrorMap map = angular_error(p, t, m);
  py::dict out = py::module_::import("json").attr("loads")(map.stats.to_json().dump());
  out["degrees"] = to_numpy(map.degrees);
  return out;
}

py::dict calibrate(const std::vector<fs::path>& inputs, const std::optional<fs::path>& rig,
                   int spheres_per_stack, double sphere_radius_mm, std::optional<double> dome_radius_mm,
                   bool allow_missing, int threads) {
  calibration::LightCalibrationOptions options;
  options.inputs = inputs;
  if (rig) options.rig = *rig;
  options.spheres_per_stack = spheres_per_stack;
  options.sphere_radius_mm = sphere_radius_mm;
  options.dome_radius_mm = dome_radius_mm;
  options.allow_missing = allow_missing;
  options.threads = threads;
  options.check();
  calibration::LightCalibrationRun run;
  {
    py::gil_scoped_release unlocked;
    run = calibration::calibrate_lights(options);
  }
  const nlohmann::json json = calibration::to_json(run.calibration);
  py::dict out = py::module_::import("json").attr("loads")(json.dump());
  Eigen::MatrixXd directions(static_cast<Eigen::Index>(run.calibration.lights.size()), 3);
  for (std::size_t i = 0; i < run.calibration.lights.size(); ++i)
    directions.row(static_cast<Eigen::Index>(i)) = run.calibration.lights[i].direction.transpose();
  out["directions"] = to_numpy(directions);
  out["seconds"] = run.seconds;
  return out;
}

}  // namespace
}  // namespace lightstage::python

PYBIND11_MODULE(lightstage, m) {
  using namespace lightstage;
  using namespace lightstage::python;
  m.doc() =
      "Lightstage: photometric stereo from light-stage captures (stacks, calibration, solvers, surfaces).";
  m.attr("__version__") = kVersion;
  static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const InputError& e) {
      PyErr_SetString(input_error.ptr(), e.what());
    } catch (const Error& e) {
      PyErr_SetString(error.ptr(), e.what());
    }
  });

  m.def(
      "methods",
      [] {
        py::list out;
        for (const auto& method : pipeline::solve_methods())
          out.append(py::make_tuple(method.name, method.help));
        return out;
      },
      "The solver methods as (name, help) pairs, in the order `lightstage solve --help` lists them.");
  m.def("load_stack", &stack_dict, py::arg("path"),
        "A stack folder (docs/stack-format.md) as a dict: images (list of arrays as stored, colour in RGB "
        "order), filenames, light_directions (N x 3), light_intensities (N x 3, r g b), mask (bool or None), "
        "normals_gt (H x W x 3 or None).");
  m.def("solve", &solve, py::arg("input"), py::arg("method") = "l2", py::arg("calibration") = py::none(),
        py::arg("distant_lights") = false,
        "Solves the stack folder `input` with `method` (see methods()), as `lightstage solve` does without "
        "writing files. Options are the solve flags with underscores: shadow_threshold, t_low, "
        "min_observations, max_iterations, threads, falloff, estimator, azimuth_from, gamma, "
        "plateau_tolerance, clamp, and for shape-prior prior, intrinsics, pixel_mm, prior_radius, "
        "prior_png_scale, sh, smoothing, refine. Returns a dict: normals (H x W x 3 float32), albedo, "
        "residual, solved (bool), confidence and coefficients (or None), summary (as summary.json holds it, "
        "with error_vs_ground_truth when the stack has Normal_gt.png).");
  m.def("integrate", &integrate, py::arg("normals"), py::arg("mask") = py::none(), py::arg("pixel_mm") = 1.0,
        py::arg("method") = "poisson", py::arg("preserve_discontinuities") = false,
        "Depth from a normal map (H x W x 3), orthographic with pixel size pixel_mm: a dict with depth "
        "(H x W float32, up to an additive constant), valid (bool), pixels and seconds.");
  m.def("angular_error", &error_stats, py::arg("predicted"), py::arg("truth"), py::arg("mask") = py::none(),
        "Angular error statistics between two normal maps (degrees): mean, median, p90, max, count, missing, "
        "and the per-pixel map under 'degrees'.");
  m.def("calibrate_lights", &calibrate, py::arg("inputs"), py::arg("rig") = py::none(),
        py::arg("spheres_per_stack") = 1, py::arg("sphere_radius_mm") = 0.0,
        py::arg("dome_radius_mm") = py::none(), py::arg("allow_missing") = false, py::arg("threads") = 0,
        "Light directions (and, from two or more sphere positions, LED positions) from chrome-sphere stacks, "
        "as `lightstage calibrate lights` computes them: the calibration as calibration.json holds it, plus "
        "directions (N x 3).");
  m.def(
      "read_pfm", [](const fs::path& path) { return to_numpy(io::read_pfm(path)); }, py::arg("path"),
      "A PFM file (albedo.pfm, residual.pfm, ...) as a float32 array, row 0 at the top.");
  m.def(
      "read_exr",
      [](const fs::path& path, const std::vector<std::string>& channels) {
        return to_numpy(io::read_exr(path, channels));
      },
      py::arg("path"), py::arg("channels"),
      "The named channels of an EXR file (normal.exr: R G B = x y z; albedo.exr: Y; depth.exr: Z) as "
      "float32.");
  m.def(
      "read_normal_map",
      [](const fs::path& path) {
        const io::DecodedNormals normals = io::read_normal_map(path);
        return py::make_tuple(to_numpy(normals.normals), mask_to_numpy(normals.valid));
      },
      py::arg("path"), "A 16-bit normal map (normal.png) as (normals H x W x 3 float32, valid bool).");
}
