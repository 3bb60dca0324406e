// `lightstage bench materials`: the dissertation's material sweep (Table 3.2's shape).
#include "commands.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/progress.hpp"
#include "lightstage/pipeline/decode_floor.hpp"
#include "lightstage/pipeline/material_sweep.hpp"
#include "lightstage/pipeline/rti_exchange.hpp"
#include "options.hpp"

#include <fmt/format.h>

#include <chrono>
#include <fstream>
#include <sstream>

namespace lightstage::cli {
namespace {

std::vector<double> parse_noise_list(const std::vector<std::string>& items) {
  std::vector<double> out;
  for (const auto& item : items) {
    if (item == "none") {
      out.push_back(-1);
      continue;
    }
    try {
      std::size_t used = 0;
      out.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      fail("--noise: '{}' is not a number or 'none'", item);
    }
  }
  return out;
}

void add_bench_holdout(CLI::App& bench) {
  struct Args {
    pipeline::HoldoutSettings settings;
    std::string input;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  auto* settings = &args->settings;
  CLI::App* sub = bench.add_subcommand(
      "holdout",
      "Leave-one-light-out relighting error on a stack of the per-pixel RTI models, PTM (biquadratic), "
      "HSH order 2 and 3, and l2 Lambertian, and of the solve methods that relight (--methods; each solved "
      "on the other lights with default settings and relit as `relight` does). The same as `relight "
      "--holdout`.\n"
      "N lights evenly spaced in the stack's order are held out one at a time; each model is fitted on the "
      "others and relit at the held-out light; relative RMSE = |relit - photo| / |photo| over the mask "
      "(grey values as solve uses them), averaged over the held-out lights.\n"
      "Example: lightstage bench holdout --input data/ballPNG --held-out 12");
  sub->add_option("--input", args->input, "stack folder")->required();
  sub->add_option("--held-out", settings->held_out, "lights held out one at a time")->capture_default_str();
  sub->add_option("--methods", settings->methods, "solve methods also measured (none: --methods none)")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--threads", settings->threads, "solver threads (0 = all)")->capture_default_str();
  sub->add_flag("--json", args->json, "print the result as one JSON object");
  sub->callback([args] {
    args->settings.input = args->input;
    const nlohmann::json r = pipeline::rti_holdout(args->settings);
    if (args->json)
      fmt::print("{}\n", r.dump());
    else
      fmt::print("{}", pipeline::format_holdout_table(r));
  });
}

void add_bench_decode(CLI::App& bench) {
  struct Args {
    std::string input;
    int threads = 0;
    OutputFlags output;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = bench.add_subcommand(
      "decode",
      "The decode floor of a stack: the time to decode every frame on --threads cores (a frame per core, "
      "each dropped once decoded, so any stack fits), the least a solve of it can take. Solve times are "
      "given as a ratio to it (scripts/bench-large-stack.py; docs/large-captures.md).\n"
      "Example: lightstage bench decode --input out/stack");
  sub->add_option("--input", args->input, "stack folder")->required();
  sub->add_option("--threads", args->threads, "decoding threads (0 = all cores)")->capture_default_str();
  add_output_flags(*sub, args->output, "seconds, frames, decoded_bytes and threads");
  sub->callback([args, sub] {
    apply_output_flags(*sub, args->output);
    const pipeline::DecodeFloor floor = pipeline::measure_decode_floor(args->input, args->threads);
    if (args->output.json) {
      fmt::print("{}\n", floor.to_json().dump());
    } else if (args->output.human()) {
      fmt::print("decoded {} frames ({:.1f} MB) on {} threads in {:.3f} s\n", floor.frames,
                 static_cast<double>(floor.decoded_bytes) / 1e6, floor.threads, floor.seconds);
    }
  });
}

}  // namespace

void add_bench(CLI::App& app) {
  CLI::App* bench = app.add_subcommand(
      "bench",
      "Measurements that reproduce the dissertation's experiments, on synthetic data (no stack needed), and "
      "held-out relighting on a stack.\n"
      "Subcommands: materials (the material sweep of Table 3.2), holdout (leave-one-light-out relighting "
      "error "
      "of PTM, HSH and l2). Speed figures of the code itself come from "
      "build/bench/bench_* (Google Benchmark).\n"
      "Example: lightstage bench materials --lights 100 --out out/sweep");
  bench->require_subcommand(1);
  struct Args {
    pipeline::MaterialSweepOptions sweep;
    std::vector<std::string> noise = {"none", "0", "0.05", "0.15", "0.3"};
    std::string out;
    OutputFlags output;
  };
  add_bench_holdout(*bench);
  add_bench_decode(*bench);
  auto args = std::make_shared<Args>();
  CLI::App* sub = bench->add_subcommand(
      "materials",
      "The material sweep of the dissertation's Chapter 3 (Table 3.2): which solver suits which material.\n"
      "\n"
      "Input: none but the flags. 1620 normals (36 azimuths x 45 elevations) are rendered exactly under "
      "random hemisphere lights for every material (Cook-Torrance roughness, Ward, Blinn-Phong, Oren-Nayar, "
      "the Fig. 2.8 two-lobe families), with noise y + lambda*y*X and 16-bit quantisation; every solver "
      "method runs on the same data.\n"
      "Output: Table 3.2's shape on stdout (rows = noise, columns = methods, mean angular error over "
      "materials), a per-material table and each method's speed; with --out, materials.json and a "
      "per-material error plot materials.png.\n"
      "\n"
      "Example: lightstage bench materials --lights 100 --noise none,0,0.05,0.15,0.3 --out out/sweep");
  sub->add_option("--light-cone", args->sweep.light_cone_deg,
                  "lights within DEG of the view axis (90: the whole hemisphere; DiLiGenT's span 43)")
      ->capture_default_str();
  sub->add_option("--lights", args->sweep.light_counts, "light counts, e.g. 25,50,100,200")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--noise", args->noise, "noise levels lambda ('none' = double precision)")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--materials", args->sweep.materials, "material presets (default: the built-in sweep)")
      ->delimiter(';');
  sub->add_option("--methods", args->sweep.methods,
                  "methods (solve --method names, plus lambert-low = l2 on the lowest T_low)")
      ->delimiter(',');
  sub->add_option("--t-low", args->sweep.t_low, "T_low of the bi-polynomial methods")->capture_default_str();
  sub->add_option("--azimuth-from", args->sweep.azimuth_from, "monotonic: isotropy or a method's normals")
      ->capture_default_str();
  sub->add_option("--refine-step", args->sweep.refine_step_deg, "monotonic: 2-D refinement step (0 = off)")
      ->capture_default_str();
  sub->add_option("--falloff", args->sweep.falloff,
                  "bi-polynomial and auto: the start's incidence fall-off ('auto' per material, 0 = Lambert)")
      ->capture_default_str();
  sub->add_option("--plateau-tolerance", args->sweep.plateau_tolerance,
                  "monotonic and auto: lowest elevation within (1 + T) x the minimum cost (0 = the minimum)")
      ->capture_default_str();
  sub->add_option("--auto-agreement", args->sweep.auto_agreement_deg,
                  "auto: answers closer than this are averaged")
      ->capture_default_str();
  sub->add_option("--auto-margin", args->sweep.auto_margin, "auto: monotonicity margin to prefer monotonic")
      ->capture_default_str();
  sub->add_option("--seed", args->sweep.seed, "lights and noise seed")->capture_default_str();
  sub->add_option("--threads", args->sweep.threads, "solver threads")->capture_default_str();
  sub->add_option("--out", args->out, "folder for materials.json and materials.png");
  add_output_flags(*sub, args->output,
                   "materials.json's content plus seconds and, with --out, the files written (outputs)");
  sub->callback([args, sub] {
    apply_output_flags(*sub, args->output);
    const auto start = std::chrono::steady_clock::now();
    args->sweep.noise = parse_noise_list(args->noise);
    args->sweep.check();
    Progress progress("bench materials", args->sweep.cells(), "runs", args->output.mode());
    const pipeline::MaterialSweepResult result = pipeline::run_material_sweep(
        args->sweep, [&progress](std::size_t cells) { progress.advance(cells); });
    progress.finish();
    nlohmann::json outputs = nlohmann::json::object();
    if (!args->out.empty()) {
      const std::filesystem::path out = args->out;
      std::filesystem::create_directories(out);
      std::ofstream(out / "materials.json") << result.to_json().dump(2) << "\n";
      pipeline::write_material_plot(out / "materials.png", result, 0, 0);
      logger("host")->info("wrote {} and {}", (out / "materials.json").string(),
                           (out / "materials.png").string());
      outputs = {{"json", (out / "materials.json").string()}, {"plot", (out / "materials.png").string()}};
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (args->output.json) {
      nlohmann::json j = result.to_json();
      j["seconds"] = seconds;
      j["outputs"] = outputs;
      fmt::print("{}\n", j.dump());
    } else if (args->output.human()) {
      for (std::size_t li = 0; li < result.options.light_counts.size(); ++li) {
        fmt::print("{}\n", result.summary_table(li));
        fmt::print("{}\n", result.material_table(li, 0));
      }
      fmt::print("pixels/s ({} threads):", result.options.threads);
      for (std::size_t k = 0; k < result.options.methods.size(); ++k)
        fmt::print(" {} {:.0f};", result.options.methods[k], result.pixels_per_second[k]);
      fmt::print("\n");
    }
  });
}

}  // namespace lightstage::cli
