#include "lightstage/testing/run.hpp"

#include "lightstage/testing/paths.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

extern char** environ;

namespace lightstage::testing {
namespace {

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

RunResult run(const std::filesystem::path& program, const std::vector<std::string>& args) {
  // Output goes to files rather than pipes: no risk of a full pipe blocking the child.
  static int counter = 0;
  const auto base = std::filesystem::temp_directory_path() /
                    ("lightstage-run-" + std::to_string(getpid()) + "-" + std::to_string(counter++));
  const auto out_path = base.string() + ".out";
  const auto err_path = base.string() + ".err";

  std::vector<std::string> argv_storage{program.string()};
  argv_storage.insert(argv_storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& arg : argv_storage) argv.push_back(arg.data());
  argv.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) throw std::runtime_error("cannot start " + program.string());

  int status = 0;
  rusage usage{};
  wait4(pid, &status, 0, &usage);  // the child's own resources, its peak memory among them
  RunResult result;
  result.peak_rss_bytes = static_cast<std::size_t>(usage.ru_maxrss) * 1024;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.out = slurp(out_path);
  result.err = slurp(err_path);
  std::filesystem::remove(out_path);
  std::filesystem::remove(err_path);
  return result;
}

RunResult run_lightstage(const std::vector<std::string>& args) { return run(bin_dir() / "lightstage", args); }

}  // namespace lightstage::testing
