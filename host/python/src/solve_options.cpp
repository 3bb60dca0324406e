#include "solve_options.hpp"

#include <pybind11/stl.h>

#include <functional>
#include <map>
#include <string>

namespace py = pybind11;

namespace lightstage::python {
namespace {

using Setter = std::function<void(pipeline::SolveSettings&, const py::handle&)>;

template <typename T>
Setter set(T pipeline::SolveSettings::*field) {
  return [field](pipeline::SolveSettings& s, const py::handle& v) { s.*field = v.cast<T>(); };
}

const std::map<std::string, Setter>& setters() {
  using S = pipeline::SolveSettings;
  static const std::map<std::string, Setter> table = {
      {"shadow_threshold", set(&S::shadow_threshold)},
      {"t_low", set(&S::t_low)},
      {"min_observations", set(&S::min_observations)},
      {"max_iterations", set(&S::max_iterations)},
      {"threads", set(&S::threads)},
      {"estimator", set(&S::estimator)},
      {"azimuth_from", set(&S::azimuth_from)},
      {"falloff",
       [](S& s, const py::handle& v) {
         s.falloff = py::isinstance<py::str>(v) ? v.cast<std::string>() : py::str(v).cast<std::string>();
       }},
      {"clamp", [](S& s, const py::handle& v) { s.no_clamp = !v.cast<bool>(); }},
      {"shadow_screen", [](S& s, const py::handle& v) { s.shadow_screen = v.cast<bool>(); }},
      {"gamma", [](S& s, const py::handle& v) { s.monotonic.gamma = v.cast<double>(); }},
      {"plateau_tolerance",
       [](S& s, const py::handle& v) { s.monotonic.plateau_tolerance = v.cast<double>(); }},
      {"prior", [](S& s, const py::handle& v) { s.shape_prior.prior = py::str(v).cast<std::string>(); }},
      {"intrinsics",
       [](S& s, const py::handle& v) { s.shape_prior.intrinsics = py::str(v).cast<std::string>(); }},
      {"pixel_mm", [](S& s, const py::handle& v) { s.shape_prior.pixel_mm = v.cast<double>(); }},
      {"prior_radius", [](S& s, const py::handle& v) { s.shape_prior.prior_radius = v.cast<double>(); }},
      {"prior_png_scale", [](S& s, const py::handle& v) { s.shape_prior.png_scale = v.cast<double>(); }},
      {"sh", [](S& s, const py::handle& v) { s.shape_prior.options.sh_dimension = v.cast<int>(); }},
      {"smoothing",
       [](S& s, const py::handle& v) { s.shape_prior.options.smoothing_sigma = v.cast<double>(); }},
      {"refine", [](S& s, const py::handle& v) { s.shape_prior.options.refine = v.cast<bool>(); }},
      {"keep_prior", [](S& s, const py::handle& v) { s.shape_prior.options.keep_prior = v.cast<bool>(); }},
      {"keep_prior_margin",
       [](S& s, const py::handle& v) { s.shape_prior.options.keep_prior_margin = v.cast<double>(); }},
  };
  return table;
}

}  // namespace

void apply_solve_options(pipeline::SolveSettings& settings, const py::kwargs& options) {
  for (const auto& [key, value] : options) {
    const std::string name = key.cast<std::string>();
    const auto setter = setters().find(name);
    if (setter == setters().end()) {
      std::string known;
      for (const auto& [option, unused] : setters()) known += (known.empty() ? "" : ", ") + option;
      throw py::type_error("solve() got an unknown option '" + name + "' (known: " + known + ")");
    }
    try {
      setter->second(settings, value);
    } catch (const py::cast_error&) {
      throw py::type_error("solve(): option '" + name + "' has the wrong type (" +
                           py::str(py::type::of(value)).cast<std::string>() + ")");
    }
  }
}

}  // namespace lightstage::python
