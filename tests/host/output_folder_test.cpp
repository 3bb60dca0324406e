// Where commands may write: not over a folder that holds something, not into
// the folder they read (however the path is spelled).
#include "lightstage/host/io/output_folder.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace lightstage::io {
namespace {

namespace fs = std::filesystem;

TEST(OutputFolder, EmptyFolderIsNewOrEmpty) {
  const fs::path dir = testing::scratch_dir();
  EXPECT_NO_THROW(require_empty_folder(dir / "new", "--out", "hint"));
  fs::create_directories(dir / "empty");
  EXPECT_NO_THROW(require_empty_folder(dir / "empty", "--out", "hint"));
  std::ofstream(dir / "empty" / "001.png") << "x";
  try {
    require_empty_folder(dir / "empty", "--out", "use --force");
    FAIL() << "a folder with a file was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not empty"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("use --force"), std::string::npos) << e.what();
  }
  EXPECT_THROW(require_empty_folder(dir / "empty" / "001.png", "--out", "hint"), InputError);
}

TEST(OutputFolder, RefusesTheInputFolderHoweverSpelled) {
  const fs::path dir = testing::scratch_dir();
  const fs::path stack = dir / "stack";
  fs::create_directories(stack / "sub");
  fs::create_directory_symlink(stack, dir / "link");
  EXPECT_THROW(require_separate_output(stack, {stack}), InputError);
  EXPECT_THROW(require_separate_output(stack.string() + "/", {stack}), InputError);
  EXPECT_THROW(require_separate_output(stack / "sub" / "..", {stack}), InputError);
  EXPECT_THROW(require_separate_output(dir / "link", {stack}), InputError);
  EXPECT_THROW(require_separate_output(stack, {dir / "link"}), InputError);
  // Inside the input, existing or not.
  EXPECT_THROW(require_separate_output(stack / "sub", {stack}), InputError);
  EXPECT_THROW(require_separate_output(dir / "link" / "result" / "deeper", {stack}), InputError);
  // Relative to the working folder.
  const fs::path relative = fs::relative(stack, fs::current_path());
  EXPECT_THROW(require_separate_output(relative, {stack}), InputError);
  try {
    require_separate_output(stack, {stack});
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--out"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(stack.string()), std::string::npos) << e.what();
  }
}

TEST(OutputFolder, AcceptsFoldersBesideTheInput) {
  const fs::path dir = testing::scratch_dir();
  fs::create_directories(dir / "stack");
  EXPECT_NO_THROW(require_separate_output(dir / "result", {dir / "stack"}));
  EXPECT_NO_THROW(require_separate_output(dir / "stack-result", {dir / "stack"}));  // a prefix, not a parent
  EXPECT_NO_THROW(require_separate_output(dir, {dir / "stack"}));                   // holds the input
  EXPECT_NO_THROW(require_separate_output(dir / "result", {fs::path()}));           // no input folder
}

}  // namespace
}  // namespace lightstage::io
