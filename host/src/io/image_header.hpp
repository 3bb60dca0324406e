#pragma once
// The size an image file declares, read from its first bytes without decoding
// it, so a stack can refuse a frame that would not fit (or would not fit in
// memory) before any pixel is decoded. Stack images are PNG, PFM, TIFF or
// camera RAW (docs/stack-format.md): a PNG is known by its signature, as the
// decoder knows it (whatever the file's name); the others by their names, as
// read_image reads them (a RAW file's size is the size read_raw gives).

#include <cstdint>
#include <filesystem>

namespace lightstage::io {

struct ImageHeader {
  std::int64_t width = 0;
  std::int64_t height = 0;
  int pixel_bytes = 0;  // a pixel decoded (read_image), when the header says: PNG and PFM; 0 = unknown
};

// Throws InputError naming the file when it is missing, is none of those, or
// its header is truncated or malformed.
ImageHeader read_image_header(const std::filesystem::path& path);

// By content: the PNG signature, whatever the name (false for a file that cannot be read).
bool is_png_file(const std::filesystem::path& path);

}  // namespace lightstage::io
