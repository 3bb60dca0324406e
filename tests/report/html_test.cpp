// The report's page pieces (host/src/report/html.hpp).
#include "report/html.hpp"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <random>
#include <vector>

namespace lightstage::report {
namespace {

std::vector<std::uint8_t> inflated(const std::vector<std::uint8_t>& stream, std::size_t size) {
  std::vector<std::uint8_t> out(size + 1);
  uLongf length = static_cast<uLongf>(out.size());
  uLong read = static_cast<uLong>(stream.size());
  // uncompress2 checks the header and the Adler-32 of everything; the browser
  // also refuses bytes after the stream's end.
  EXPECT_EQ(uncompress2(out.data(), &length, stream.data(), &read), Z_OK);
  EXPECT_EQ(read, stream.size());
  out.resize(length);
  return out;
}

// Payloads are deflated in pieces side by side: one zlib stream whatever the
// count of pieces, the same bytes every time.
TEST(ReportHtml, ZlibStreamOfPiecesInflatesToTheBytes) {
  constexpr std::size_t kPiece = kDeflatePiece;
  std::mt19937 rng(3);
  for (const std::size_t size :
       {std::size_t{0}, std::size_t{1}, kPiece - 1, kPiece, kPiece + 1, 2 * kPiece + kPiece / 2}) {
    SCOPED_TRACE(size);
    std::vector<std::uint8_t> bytes(size);
    // Runs to find and noise to keep: both kinds of deflate block.
    for (std::size_t i = 0; i < size; ++i)
      bytes[i] = (i / 1000) % 2 == 0 ? static_cast<std::uint8_t>(i % 7) : static_cast<std::uint8_t>(rng());
    const std::vector<std::uint8_t> stream = zlib_compress(bytes);
    ASSERT_GE(stream.size(), 6u);
    EXPECT_EQ(stream[0], 0x78);
    EXPECT_EQ((stream[0] * 256 + stream[1]) % 31, 0);
    EXPECT_EQ(inflated(stream, size), bytes);
    EXPECT_EQ(zlib_compress(bytes), stream);
    if (size > kPiece) {
      EXPECT_LT(stream.size(), size * 3 / 4);  // the pieces compress
    }
  }
}

}  // namespace
}  // namespace lightstage::report
