#pragma once
// Another program running beside this one (lightstage-sim and lightstage-domed
// under `lightstage demo`, any of our programs in integration tests). Its
// standard output and error go to one log file that the parent can wait on.

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <sys/types.h>

namespace lightstage {

class ChildProcess {
 public:
  // Starts `program` with `args`; output goes to `log`. Throws Error when it
  // cannot start. The child gets SIGTERM when the thread that started it ends
  // (PR_SET_PDEATHSIG): start children from the main thread.
  ChildProcess(const std::filesystem::path& program, const std::vector<std::string>& args,
               std::filesystem::path log);
  // Kills (SIGKILL) and reaps the child if it still runs.
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // Waits until the log contains `text`; false if the child exits or time runs out first.
  bool wait_for_output(const std::string& text, std::chrono::milliseconds timeout) const;
  void signal(int signal_number) const;
  // The exit code (128 + signal when killed by one; -1 when reaped elsewhere),
  // or nullopt if still running after `timeout`.
  std::optional<int> wait(std::chrono::milliseconds timeout);
  // SIGTERM, then SIGKILL when it has not exited within `grace`; returns the exit code.
  int terminate(std::chrono::milliseconds grace);
  bool running();
  std::string output() const;
  const std::filesystem::path& log() const { return log_; }
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  std::optional<int> exit_code_;
  std::filesystem::path log_;
};

// The folder of the running executable (/proc/self/exe), where the project's
// programs sit side by side in a build or an install.
std::filesystem::path own_program_dir();

}  // namespace lightstage
