#pragma once
// `lightstage solve --method NAME`: the table of solver methods. Each entry
// is one line — a name, a help line and a function from observations plus the
// parsed flags to a SolveResult — so a new method is one entry here (and its
// function) and nothing else in the CLI changes.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/solve_result.hpp"
#include "options.hpp"

#include <string>
#include <vector>

namespace lightstage::cli {

struct SolveMethod {
  const char* name;
  const char* help;
  SolveResult (*solve)(const Observations& observations, const SolveArgs& args);
};

// Every method, in the order --help lists them.
const std::vector<SolveMethod>& solve_methods();
std::vector<std::string> solve_method_names();
// Throws InputError naming --method and the known names.
const SolveMethod& find_solve_method(const std::string& name);

}  // namespace lightstage::cli
