#include "lightstage/common/printable.hpp"

#include <gtest/gtest.h>

#include <string>

namespace lightstage {
namespace {

TEST(Printable, ShortPlainTextIsUnchanged) { EXPECT_EQ(printable("dome-96 µ"), "dome-96 µ"); }

TEST(Printable, ControlCharactersAreEscaped) {
  EXPECT_EQ(printable("a\nb\tc\x1b[2J\x7f\\"), "a\\nb\\tc\\x1b[2J\\x7f\\\\");
}

TEST(Printable, LongValuesAreCut) {
  const std::string shown = printable(std::string(50'000'000, 'x'));
  EXPECT_EQ(shown, std::string(kPrintableChars, 'x') + "...");
}

TEST(Printable, CutsNeitherAnEscapeNorAUtf8Character) {
  EXPECT_EQ(printable("abc\n", 4), "abc...");
  EXPECT_EQ(printable("ab\xc2\xb5", 3), "ab...");
  EXPECT_EQ(printable("abcd", 4), "abcd");
}

}  // namespace
}  // namespace lightstage
