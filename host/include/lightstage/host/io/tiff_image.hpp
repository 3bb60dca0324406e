#pragma once
// TIFF images through libtiff, read as stored: what scanners, tethering
// programs and raw converters write for linear captures. Taken: 8- and 16-bit
// unsigned integer or 32-bit float samples, grey (min-is-black) or RGB, with
// an extra (alpha) sample dropped, in strips or tiles, interleaved or planar,
// with any compression libtiff decodes. Refused with the reason: palette,
// CMYK, YCbCr and CFA (raw mosaic) images, min-is-white grey, signed or
// other sample sizes. A DNG is a TIFF too, but is read as RAW (raw_image.hpp).

#include <opencv2/core.hpp>

#include <filesystem>

namespace lightstage::io {

// A .tif / .tiff file (case-insensitive).
bool is_tiff_file(const std::filesystem::path& path);

// The first image of `path`: CV_8U / CV_16U / CV_32F with 1 or 3 (BGR)
// channels. Throws InputError naming the file and, where it has one, the
// libtiff message, for a missing, truncated or corrupt file or a layout above.
cv::Mat read_tiff(const std::filesystem::path& path);

// Width and height of the first image, from its directory alone.
cv::Size read_tiff_size(const std::filesystem::path& path);

}  // namespace lightstage::io
