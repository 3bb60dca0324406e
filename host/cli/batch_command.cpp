// `lightstage batch`: every capture of a folder solved with the same flags.
#include "commands.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/pipeline/batch_solve.hpp"
#include "options.hpp"

#include <fmt/format.h>

#include <memory>

namespace lightstage::cli {

void add_batch(CLI::App& app) {
  auto args = std::make_shared<SolveCommandArgs>();
  CLI::App* sub = app.add_subcommand(
      "batch",
      "Solve every capture in a folder with the same flags, one result folder each, and one summary.\n"
      "\n"
      "Input: a folder whose subfolders are stack folders (holding filenames.txt), or hold one as stack/ "
      "(what `capture` and `demo` write). Each is solved as `solve` would into --out/NAME; --out/batch.json "
      "lists every capture's status, counts and error against ground truth, rewritten after each one. Run "
      "again, the batch skips captures whose result is complete (same input and method) and solves the "
      "others: failed or interrupted ones. A capture that fails is reported and the batch goes on; the exit "
      "status is 1 when any failed.\n"
      "\n"
      "Example: lightstage batch --input dome/2026-12 --method robust --out results/2026-12");
  sub->add_option("--input", args->input, "folder of captures")->required();
  sub->add_option("--out", args->out, "folder of results (one subfolder per capture)")->required();
  add_solve_flags(*sub, args->solve);
  add_solve_calibration_flags(*sub, args->calibration);
  add_output_flags(*sub, args->output, "batch.json");
  sub->callback([args, sub] {
    apply_output_flags(*sub, args->output);
    args->solve.resolve();
    const auto report = pipeline::solve_batch(
        args->input, args->solve, args->out, args->calibration,
        [&](const pipeline::BatchOutcome& c, std::size_t index, std::size_t total) {
          if (!args->output.human()) return;
          std::string what = c.status;
          if (c.status == "failed") what += ": " + c.error;
          if (c.summary.is_object() && c.summary.contains("error_vs_ground_truth"))
            what += fmt::format(" (mean error {:.2f} deg)",
                                c.summary["error_vs_ground_truth"].value("mean_deg", 0.0));
          fmt::print("[{}/{}] {}: {} in {:.1f} s\n", index + 1, total, c.name, what, c.seconds);
        });
    if (args->output.json)
      fmt::print("{}\n", report.to_json().dump());
    else if (args->output.human())
      fmt::print("{} solved, {} done before, {} failed -> {}/batch.json\n", report.solved, report.done_before,
                 report.failed, args->out);
    if (report.failed > 0)
      throw Error(fmt::format("{} of {} captures failed (their errors are in {}/batch.json)", report.failed,
                              report.captures.size(), args->out));
  });
}

}  // namespace lightstage::cli
