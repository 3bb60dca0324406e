#include "lightstage/host/io/tiff_image.hpp"

#include "io/file_extension.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/stack_io.hpp"

#include <tiffio.h>

#include <algorithm>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <system_error>
#include <vector>

namespace lightstage::io {
namespace {

// The largest buffer libtiff may allocate for one strip or tile of a hostile file.
constexpr tmsize_t kMaxTiffAllocation = tmsize_t{1} << 30;

// libtiff's first error message for the file being read.
int keep_first_error(TIFF*, void* user_data, const char* module, const char* format, va_list args) {
  auto* message = static_cast<std::string*>(user_data);
  if (message->empty()) {
    char text[512];
    std::vsnprintf(text, sizeof text, format, args);
    *message = module != nullptr && *module != '\0' ? std::string(module) + ": " + text : std::string(text);
  }
  return 1;
}
int ignore_warning(TIFF*, void*, const char*, const char*, va_list) { return 1; }

struct TiffCloser {
  void operator()(TIFF* tiff) const { TIFFClose(tiff); }
};
using TiffHandle = std::unique_ptr<TIFF, TiffCloser>;

class TiffFile {
 public:
  explicit TiffFile(const std::filesystem::path& path) : path_(path) {
    std::error_code error;
    if (!std::filesystem::exists(path, error)) fail("{}: no such file", path.string());
    if (!std::filesystem::is_regular_file(path, error)) fail("{}: not a regular file", path.string());
    std::unique_ptr<TIFFOpenOptions, void (*)(TIFFOpenOptions*)> options(TIFFOpenOptionsAlloc(),
                                                                         TIFFOpenOptionsFree);
    TIFFOpenOptionsSetErrorHandlerExtR(options.get(), keep_first_error, &message_);
    TIFFOpenOptionsSetWarningHandlerExtR(options.get(), ignore_warning, nullptr);
    TIFFOpenOptionsSetMaxSingleMemAlloc(options.get(), kMaxTiffAllocation);
    tiff_.reset(TIFFOpenExt(path.c_str(), "r", options.get()));
    if (!tiff_) fail_here("not a readable TIFF file");
  }

  TIFF* get() const { return tiff_.get(); }

  [[noreturn]] void fail_here(const std::string& what) const {
    if (message_.empty()) fail("{}: {}", path_.string(), what);
    fail("{}: {} ({})", path_.string(), what, message_);
  }

  template <typename T>
  T field(ttag_t tag, const char* name) const {
    T value{};
    if (TIFFGetField(tiff_.get(), tag, &value) != 1) fail_here(fmt::format("no {} tag", name));
    return value;
  }
  template <typename T>
  T field_or_default(ttag_t tag) const {
    T value{};
    TIFFGetFieldDefaulted(tiff_.get(), tag, &value);
    return value;
  }

 private:
  std::filesystem::path path_;
  std::string message_;
  TiffHandle tiff_;
};

struct Layout {
  int width = 0, height = 0;
  int samples = 1;   // per pixel in the file
  int channels = 1;  // kept: 1 (grey) or 3 (RGB)
  int bytes = 1;     // per sample
  bool planar = false;
  int cv_depth = CV_8U;
};

cv::Size size_of(const TiffFile& file) {
  const auto width = file.field<std::uint32_t>(TIFFTAG_IMAGEWIDTH, "ImageWidth");
  const auto height = file.field<std::uint32_t>(TIFFTAG_IMAGELENGTH, "ImageLength");
  if (width == 0 || height == 0 || width > kMaxImageSide || height > kMaxImageSide)
    file.fail_here(fmt::format("image of {}x{} pixels (each side 1 to {})", width, height, kMaxImageSide));
  return {static_cast<int>(width), static_cast<int>(height)};
}

Layout layout_of(const TiffFile& file) {
  Layout layout;
  const cv::Size size = size_of(file);
  layout.width = size.width;
  layout.height = size.height;
  layout.samples = file.field_or_default<std::uint16_t>(TIFFTAG_SAMPLESPERPIXEL);
  const auto bits = file.field_or_default<std::uint16_t>(TIFFTAG_BITSPERSAMPLE);
  const auto format = file.field_or_default<std::uint16_t>(TIFFTAG_SAMPLEFORMAT);
  const auto photometric = file.field<std::uint16_t>(TIFFTAG_PHOTOMETRIC, "PhotometricInterpretation");
  layout.planar = file.field_or_default<std::uint16_t>(TIFFTAG_PLANARCONFIG) == PLANARCONFIG_SEPARATE;

  if (format == SAMPLEFORMAT_UINT && (bits == 8 || bits == 16)) {
    layout.cv_depth = bits == 8 ? CV_8U : CV_16U;
  } else if (format == SAMPLEFORMAT_IEEEFP && bits == 32) {
    layout.cv_depth = CV_32F;
  } else {
    file.fail_here(fmt::format("{}-bit {} samples; 8- or 16-bit unsigned or 32-bit float are read", bits,
                               format == SAMPLEFORMAT_INT      ? "signed"
                               : format == SAMPLEFORMAT_IEEEFP ? "float"
                                                               : "unsigned"));
  }
  layout.bytes = bits / 8;
  switch (photometric) {
    case PHOTOMETRIC_MINISBLACK:
      layout.channels = 1;
      break;
    case PHOTOMETRIC_RGB:
      layout.channels = 3;
      break;
    case PHOTOMETRIC_MINISWHITE:
      file.fail_here("min-is-white grey (an inverted scan), not a linear capture");
    case PHOTOMETRIC_PALETTE:
      file.fail_here("a palette image, not a linear capture");
    case PHOTOMETRIC_YCBCR:
      file.fail_here("YCbCr samples (a JPEG-compressed rendering), not a linear capture");
    case PHOTOMETRIC_CFA:
      file.fail_here("a raw colour-filter mosaic; name it .dng to read it as RAW");
    default:
      file.fail_here(fmt::format("photometric interpretation {} (grey or RGB are read)", photometric));
  }
  if (layout.samples < layout.channels || layout.samples > 8)
    file.fail_here(fmt::format("{} samples per pixel for a {} image", layout.samples,
                               layout.channels == 1 ? "grey" : "RGB"));
  return layout;
}

// Copies `count` pixels of one sample plane (planar) or of every sample
// (interleaved) from `in` into row `out` (BGR order for colour).
void copy_pixels(const Layout& layout, const std::uint8_t* in, int count, int sample, std::uint8_t* out) {
  const int stride = layout.planar ? 1 : layout.samples;
  const int first = layout.planar ? sample : 0;
  const int last = layout.planar ? sample + 1 : layout.channels;
  for (int s = first; s < std::min(last, layout.channels); ++s) {
    const int channel = layout.channels == 3 ? 2 - s : 0;
    const int offset = layout.planar ? 0 : s;
    for (int x = 0; x < count; ++x)
      std::memcpy(out + (static_cast<std::size_t>(x) * layout.channels + channel) * layout.bytes,
                  in + (static_cast<std::size_t>(x) * stride + offset) * layout.bytes, layout.bytes);
  }
}

void read_strips(const TiffFile& file, const Layout& layout, cv::Mat& out) {
  const tmsize_t size = TIFFScanlineSize(file.get());
  const std::size_t needed =
      static_cast<std::size_t>(layout.width) * (layout.planar ? 1 : layout.samples) * layout.bytes;
  if (size <= 0 || static_cast<std::size_t>(size) < needed)
    file.fail_here("scanline size does not fit the image");
  std::vector<std::uint8_t> line(static_cast<std::size_t>(size));
  const int planes = layout.planar ? std::min(layout.samples, layout.channels) : 1;
  for (int plane = 0; plane < planes; ++plane) {
    for (int y = 0; y < layout.height; ++y) {
      if (TIFFReadScanline(file.get(), line.data(), static_cast<std::uint32_t>(y),
                           static_cast<std::uint16_t>(plane)) != 1)
        file.fail_here(fmt::format("cannot read row {}", y));
      copy_pixels(layout, line.data(), layout.width, plane, out.ptr<std::uint8_t>(y));
    }
  }
}

void read_tiles(const TiffFile& file, const Layout& layout, cv::Mat& out) {
  const auto tile_width = static_cast<int>(file.field<std::uint32_t>(TIFFTAG_TILEWIDTH, "TileWidth"));
  const auto tile_height = static_cast<int>(file.field<std::uint32_t>(TIFFTAG_TILELENGTH, "TileLength"));
  const tmsize_t size = TIFFTileSize(file.get());
  const std::size_t needed = static_cast<std::size_t>(tile_width) * static_cast<std::size_t>(tile_height) *
                             (layout.planar ? 1 : layout.samples) * layout.bytes;
  // A tile larger than the image (rounded up to libtiff's multiple of 16) only costs memory.
  const auto round_up = [](int side) { return (side + 15) / 16 * 16; };
  if (tile_width <= 0 || tile_height <= 0 || tile_width > round_up(layout.width) ||
      tile_height > round_up(layout.height) || size <= 0 || static_cast<std::size_t>(size) < needed ||
      size > kMaxTiffAllocation)
    file.fail_here(fmt::format("tiles of {}x{} do not fit a {}x{} image", tile_width, tile_height,
                               layout.width, layout.height));
  std::vector<std::uint8_t> tile(static_cast<std::size_t>(size));
  const std::size_t tile_row = needed / static_cast<std::size_t>(tile_height);
  const int planes = layout.planar ? std::min(layout.samples, layout.channels) : 1;
  for (int plane = 0; plane < planes; ++plane) {
    for (int y0 = 0; y0 < layout.height; y0 += tile_height) {
      for (int x0 = 0; x0 < layout.width; x0 += tile_width) {
        if (TIFFReadTile(file.get(), tile.data(), static_cast<std::uint32_t>(x0),
                         static_cast<std::uint32_t>(y0), 0, static_cast<std::uint16_t>(plane)) < 0)
          file.fail_here(fmt::format("cannot read the tile at ({}, {})", x0, y0));
        const int rows = std::min(tile_height, layout.height - y0);
        const int cols = std::min(tile_width, layout.width - x0);
        for (int r = 0; r < rows; ++r) {
          std::uint8_t* row =
              out.ptr<std::uint8_t>(y0 + r) + static_cast<std::size_t>(x0) * layout.channels * layout.bytes;
          copy_pixels(layout, tile.data() + static_cast<std::size_t>(r) * tile_row, cols, plane, row);
        }
      }
    }
  }
}

}  // namespace

bool is_tiff_file(const std::filesystem::path& path) {
  const std::string extension = lower_extension(path);
  return extension == ".tif" || extension == ".tiff";
}

cv::Mat read_tiff(const std::filesystem::path& path) {
  try {
    const TiffFile file(path);
    const Layout layout = layout_of(file);
    cv::Mat out(layout.height, layout.width, CV_MAKETYPE(layout.cv_depth, layout.channels));
    if (TIFFIsTiled(file.get()))
      read_tiles(file, layout, out);
    else
      read_strips(file, layout, out);
    if (layout.cv_depth == CV_32F && !cv::checkRange(out))
      fail("{}: float samples hold NaN or infinity", path.string());
    return out;
  } catch (const std::bad_alloc&) {
    fail("{}: too large to decode in the memory available", path.string());
  } catch (const cv::Exception& e) {
    fail("{}: cannot decode ({})", path.string(), e.what());
  }
}

cv::Size read_tiff_size(const std::filesystem::path& path) { return size_of(TiffFile(path)); }

}  // namespace lightstage::io
