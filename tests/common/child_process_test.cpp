#include "lightstage/common/child_process.hpp"

#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <signal.h>

#include <filesystem>

namespace lightstage {
namespace {

namespace fs = std::filesystem;

// Under the build tree, not /tmp: nothing is left behind on the machine.
fs::path scratch_log(const std::string& name) { return lightstage::testing::scratch_dir() / name; }

// A parent that takes SIGTERM with sigwait blocks it; its children must still hear it.
TEST(ChildProcess, ChildOfAParentBlockingSigtermStillEndsOnIt) {
  sigset_t terminate;
  sigemptyset(&terminate);
  sigaddset(&terminate, SIGTERM);
  sigset_t before;
  ASSERT_EQ(pthread_sigmask(SIG_BLOCK, &terminate, &before), 0);
  {
    ChildProcess child("/bin/sleep", {"30"}, scratch_log("sleep.log"));
    child.signal(SIGTERM);
    const auto code = child.wait(std::chrono::seconds(5));
    ASSERT_TRUE(code.has_value()) << "the child ignored SIGTERM: it inherited the blocked mask";
    EXPECT_EQ(*code, 128 + SIGTERM);
  }
  pthread_sigmask(SIG_SETMASK, &before, nullptr);
}

TEST(ChildProcess, ProgramThatCannotStartIsNamed) {
  try {
    ChildProcess child("/nonexistent/program", {}, scratch_log("missing.log"));
    FAIL() << "started a program that does not exist";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/program"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lightstage
