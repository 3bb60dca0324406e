#pragma once
// Test TIFFs of every layout the reader takes (strips of 3 rows or square
// tiles, interleaved or planar, an alpha sample, any compression), written
// with libtiff for tiff_image_test and row_reader_test.

#include <gtest/gtest.h>
#include <tiffio.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <vector>

namespace lightstage::testing {

// How a test TIFF is laid out on disk.
struct Written {
  int bits = 16;
  int format = SAMPLEFORMAT_UINT;
  int photometric = PHOTOMETRIC_RGB;
  int extra_samples = 0;  // an alpha channel after the colour samples
  bool planar = false;
  int tile = 0;  // tile side; 0 = strips
  int compression = COMPRESSION_NONE;
};

// Writes `rgb` (file order) with `alpha` appended when the layout has an extra sample.
inline void write_tiff(const std::filesystem::path& path, const cv::Mat& rgb, const Written& w) {
  TIFF* tiff = TIFFOpen(path.c_str(), "w");
  ASSERT_NE(tiff, nullptr);
  const int colour = rgb.channels();
  const int samples = colour + w.extra_samples;
  TIFFSetField(tiff, TIFFTAG_IMAGEWIDTH, static_cast<std::uint32_t>(rgb.cols));
  TIFFSetField(tiff, TIFFTAG_IMAGELENGTH, static_cast<std::uint32_t>(rgb.rows));
  TIFFSetField(tiff, TIFFTAG_BITSPERSAMPLE, static_cast<std::uint16_t>(w.bits));
  TIFFSetField(tiff, TIFFTAG_SAMPLEFORMAT, static_cast<std::uint16_t>(w.format));
  TIFFSetField(tiff, TIFFTAG_SAMPLESPERPIXEL, static_cast<std::uint16_t>(samples));
  TIFFSetField(tiff, TIFFTAG_PHOTOMETRIC, static_cast<std::uint16_t>(w.photometric));
  TIFFSetField(tiff, TIFFTAG_PLANARCONFIG,
               static_cast<std::uint16_t>(w.planar ? PLANARCONFIG_SEPARATE : PLANARCONFIG_CONTIG));
  TIFFSetField(tiff, TIFFTAG_COMPRESSION, static_cast<std::uint16_t>(w.compression));
  if (w.extra_samples > 0) {
    const std::uint16_t kinds[] = {EXTRASAMPLE_UNASSALPHA};
    TIFFSetField(tiff, TIFFTAG_EXTRASAMPLES, static_cast<std::uint16_t>(1), kinds);
  }
  if (w.photometric == PHOTOMETRIC_PALETTE) {
    std::vector<std::uint16_t> map(std::size_t{1} << w.bits, 0);
    TIFFSetField(tiff, TIFFTAG_COLORMAP, map.data(), map.data(), map.data());
  }
  const std::size_t bytes = static_cast<std::size_t>(w.bits / 8);
  // Sample s of pixel (y, x), alpha = a constant.
  const auto sample = [&](int y, int x, int s, std::uint8_t* out) {
    if (s < colour) {
      std::memcpy(out, rgb.ptr<std::uint8_t>(y) + (static_cast<std::size_t>(x) * colour + s) * bytes, bytes);
    } else {
      std::memset(out, 0x7f, bytes);
    }
  };
  const int planes = w.planar ? samples : 1;
  const int per_pixel = w.planar ? 1 : samples;
  if (w.tile > 0) {
    TIFFSetField(tiff, TIFFTAG_TILEWIDTH, static_cast<std::uint32_t>(w.tile));
    TIFFSetField(tiff, TIFFTAG_TILELENGTH, static_cast<std::uint32_t>(w.tile));
    std::vector<std::uint8_t> tile(static_cast<std::size_t>(w.tile * w.tile * per_pixel) * bytes);
    for (int plane = 0; plane < planes; ++plane)
      for (int y0 = 0; y0 < rgb.rows; y0 += w.tile)
        for (int x0 = 0; x0 < rgb.cols; x0 += w.tile) {
          std::fill(tile.begin(), tile.end(), 0);
          for (int r = 0; r < w.tile && y0 + r < rgb.rows; ++r)
            for (int c = 0; c < w.tile && x0 + c < rgb.cols; ++c)
              for (int s = 0; s < per_pixel; ++s)
                sample(y0 + r, x0 + c, w.planar ? plane : s,
                       tile.data() + (static_cast<std::size_t>(r * w.tile + c) * per_pixel + s) * bytes);
          ASSERT_GE(TIFFWriteTile(tiff, tile.data(), static_cast<std::uint32_t>(x0),
                                  static_cast<std::uint32_t>(y0), 0, static_cast<std::uint16_t>(plane)),
                    0);
        }
  } else {
    TIFFSetField(tiff, TIFFTAG_ROWSPERSTRIP, static_cast<std::uint32_t>(3));
    std::vector<std::uint8_t> line(static_cast<std::size_t>(rgb.cols * per_pixel) * bytes);
    for (int plane = 0; plane < planes; ++plane)
      for (int y = 0; y < rgb.rows; ++y) {
        for (int x = 0; x < rgb.cols; ++x)
          for (int s = 0; s < per_pixel; ++s)
            sample(y, x, w.planar ? plane : s,
                   line.data() + (static_cast<std::size_t>(x) * per_pixel + s) * bytes);
        ASSERT_EQ(TIFFWriteScanline(tiff, line.data(), static_cast<std::uint32_t>(y),
                                    static_cast<std::uint16_t>(plane)),
                  1);
      }
  }
  TIFFClose(tiff);
}

}  // namespace lightstage::testing
