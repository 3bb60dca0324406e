#pragma once
// A program of the build running beside the test (lightstage-sim,
// lightstage-domed, lightstage), for integration tests across processes. Its
// standard output and error go to one log file that the test can wait on.

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <sys/types.h>

namespace lightstage::testing {

class ChildProcess {
 public:
  // Starts `program` with `args`; output goes to `log`.
  ChildProcess(const std::filesystem::path& program, const std::vector<std::string>& args,
               std::filesystem::path log);
  // Kills (SIGKILL) and reaps the child if it still runs.
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // Waits until the log contains `text`; false if the child exits or time runs out first.
  bool wait_for_output(const std::string& text, std::chrono::milliseconds timeout) const;
  void signal(int signal_number) const;
  // The exit code (128 + signal when killed by one), or nullopt if still running after `timeout`.
  std::optional<int> wait(std::chrono::milliseconds timeout);
  bool running();
  std::string output() const;
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  std::optional<int> exit_code_;
  std::filesystem::path log_;
};

}  // namespace lightstage::testing
