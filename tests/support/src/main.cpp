// The one test main: GoogleTest plus the project's logging kept quiet unless
// LIGHTSTAGE_TEST_LOG is set (e.g. LIGHTSTAGE_TEST_LOG=debug).
#include "lightstage/common/log.hpp"

#include <gtest/gtest.h>

#include <cstdlib>

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  const char* level = std::getenv("LIGHTSTAGE_TEST_LOG");
  lightstage::set_log_level(level ? level : "warn");
  return RUN_ALL_TESTS();
}
