#pragma once
// The dissertation's synthetic protocol (Chapters 2–3; ALGORITHMS.md §2–3):
// 1620 normals (36 azimuths × 45 elevations, 2°..90°), random lights on the
// hemisphere, each material rendered exactly (sim BRDFs, no image), values
// normalised by the material's maximum, then noise y + λ·y·X (X ~ N(0,1)) and
// 16-bit quantisation (λ = 0: quantisation only; "none": double precision).
// Every method of the solve table runs on the same data; the result is the
// mean angular error per (light count, noise, material, method).

#include "lightstage/host/solvers/auto.hpp"
#include "lightstage/host/solvers/monotonic.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace lightstage::pipeline {

struct MaterialSweepOptions {
  std::vector<std::string> materials;  // sim material presets; empty = default_sweep_materials()
  std::vector<std::string> methods;    // solve methods + "lambert-low"; empty = default_sweep_methods()
  std::vector<int> light_counts = {100};
  double light_cone_deg = 90;  // lights within this angle of the view axis (90: the hemisphere)
  std::vector<double> noise = {-1, 0, 0.05, 0.15, 0.3};  // λ; −1 = no noise, no quantisation
  double t_low = 0.25;                                   // bi-polynomial, auto and lambert-low
  // monotonic's --azimuth-from: a robust Lambertian normal's azimuth (docs/solvers.md compares the choices).
  std::string azimuth_from = "robust";
  double refine_step_deg = MonotonicOptions{}.refine_step_deg;      // monotonic's 2-D refinement (0 = off)
  double plateau_tolerance = MonotonicOptions{}.plateau_tolerance;  // monotonic's step 3 (0 = argmin)
  std::string falloff = "auto";  // bi-polynomial and auto: --falloff auto|K
  double auto_agreement_deg = AutoOptions{}.agreement_deg;
  double auto_margin = AutoOptions{}.monotonic_margin;
  std::uint64_t seed = 1;
  int threads = 2;

  void check() const;  // throws InputError naming the flag
  // Solves the sweep runs: light counts × noise levels × materials × methods
  // (the defaults' sizes when materials or methods are empty).
  std::size_t cells() const;
};

std::vector<std::string> default_sweep_materials();
std::vector<std::string> default_sweep_methods();

struct MaterialSweepResult {
  MaterialSweepOptions options;
  // errors[light][noise][material][method]: mean angular error in degrees.
  std::vector<std::vector<std::vector<std::vector<double>>>> errors;
  // pixels per second per method, summed over the whole sweep.
  std::vector<double> pixels_per_second;

  nlohmann::json to_json() const;
  // Table 3.2's shape: rows = noise levels, columns = methods, mean over materials.
  std::string summary_table(std::size_t light_index) const;
  // One row per material at the given light count and noise.
  std::string material_table(std::size_t light_index, std::size_t noise_index) const;
};

// `on_cells`, when set, is called with 1 after every cell (one method on one
// rendered material), on the caller's thread.
MaterialSweepResult run_material_sweep(const MaterialSweepOptions& options,
                                       const std::function<void(std::size_t cells)>& on_cells = {});

// A per-material error plot (PNG): materials on x (sorted by the first
// method listed), one coloured line per method.
void write_material_plot(const std::filesystem::path& path, const MaterialSweepResult& result,
                         std::size_t light_index, std::size_t noise_index);

}  // namespace lightstage::pipeline
