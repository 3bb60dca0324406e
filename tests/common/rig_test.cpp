#include "lightstage/common/rig.hpp"
#include <gtest/gtest.h>
TEST(Rig, Placeholder) { SUCCEED(); }
