#pragma once
// Runs a program of the build (e.g. bin/lightstage) as a child process, for
// end-to-end tests of the CLI: what it printed and how it exited.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace lightstage::testing {

struct RunResult {
  int exit_code = -1;              // the exit status, or 128 + signal number
  std::string out;                 // standard output
  std::string err;                 // standard error
  std::size_t peak_rss_bytes = 0;  // the child's peak resident memory
};

RunResult run(const std::filesystem::path& program, const std::vector<std::string>& args);

// bin/lightstage with `args`.
RunResult run_lightstage(const std::vector<std::string>& args);

}  // namespace lightstage::testing
