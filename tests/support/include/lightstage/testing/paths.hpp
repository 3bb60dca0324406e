#pragma once
// Where tests find the source tree, the shared real data and scratch space.

#include <filesystem>
#include <string>

namespace lightstage::testing {

// The project's source directory (LIGHTSTAGE_SOURCE_DIR, set by CTest).
std::filesystem::path source_dir();
// ../shared/data beside the checkout; empty if it is not there.
std::filesystem::path shared_data_dir();
// A fresh, empty directory under the build tree, unique to the running test.
std::filesystem::path scratch_dir();
// A short folder under /tmp for Unix sockets (their paths must stay under 108
// bytes), private to this test process and removed when it exits.
std::filesystem::path socket_dir();

// The build directory's bin/ (the programs under test).
std::filesystem::path bin_dir();

// A file's bytes ("" when it cannot be read: the test's own expectation then fails).
std::string read_text(const std::filesystem::path& file);

}  // namespace lightstage::testing
