#include "lightstage/host/io/tiff_image.hpp"

#include "io/file_extension.hpp"
#include "io/row_readers.hpp"
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

// A TIFF's rows a block at a time: a strip, or a row of tiles, decoded once
// (every sample plane) into rows of the output type and kept until a band
// needs the next block.
class TiffRows final : public RowReader {
 public:
  explicit TiffRows(const std::filesystem::path& path) : TiffRows(path, std::make_unique<TiffFile>(path)) {}

 private:
  // `file` is moved from only after its layout is read.
  TiffRows(const std::filesystem::path& path, std::unique_ptr<TiffFile>&& file)
      : TiffRows(path, layout_of(*file), std::move(file)) {}
  TiffRows(const std::filesystem::path& path, const Layout& layout, std::unique_ptr<TiffFile>&& file)
      : RowReader(path, {layout.width, layout.height}, CV_MAKETYPE(layout.cv_depth, layout.channels)),
        file_(std::move(file)),
        layout_(layout) {
    tiled_ = TIFFIsTiled(file_->get()) != 0;
    if (tiled_) {
      tile_width_ = static_cast<int>(file_->field<std::uint32_t>(TIFFTAG_TILEWIDTH, "TileWidth"));
      block_rows_ = static_cast<int>(file_->field<std::uint32_t>(TIFFTAG_TILELENGTH, "TileLength"));
      const tmsize_t size = TIFFTileSize(file_->get());
      const std::size_t needed = static_cast<std::size_t>(tile_width_) *
                                 static_cast<std::size_t>(block_rows_) *
                                 (layout_.planar ? 1 : layout_.samples) * layout_.bytes;
      // A tile larger than the image (rounded up to libtiff's multiple of 16) only costs memory.
      const auto round_up = [](int side) { return (side + 15) / 16 * 16; };
      if (tile_width_ <= 0 || block_rows_ <= 0 || tile_width_ > round_up(layout_.width) ||
          block_rows_ > round_up(layout_.height) || size <= 0 || static_cast<std::size_t>(size) < needed ||
          size > kMaxTiffAllocation)
        file_->fail_here(fmt::format("tiles of {}x{} do not fit a {}x{} image", tile_width_, block_rows_,
                                     layout_.width, layout_.height));
      buffer_.resize(static_cast<std::size_t>(size));
      unit_row_bytes_ = needed / static_cast<std::size_t>(block_rows_);
    } else {
      const auto rows_per_strip = file_->field_or_default<std::uint32_t>(TIFFTAG_ROWSPERSTRIP);
      block_rows_ = static_cast<int>(std::min<std::uint32_t>(rows_per_strip == 0 ? 1 : rows_per_strip,
                                                             static_cast<std::uint32_t>(layout_.height)));
      const tmsize_t line = TIFFScanlineSize(file_->get());
      unit_row_bytes_ =
          static_cast<std::size_t>(layout_.width) * (layout_.planar ? 1 : layout_.samples) * layout_.bytes;
      if (line <= 0 || static_cast<std::size_t>(line) < unit_row_bytes_ ||
          static_cast<std::size_t>(line) * static_cast<std::size_t>(block_rows_) >
              static_cast<std::size_t>(kMaxTiffAllocation))
        file_->fail_here("scanline size does not fit the image");
      unit_row_bytes_ = static_cast<std::size_t>(line);
      buffer_.resize(unit_row_bytes_ * static_cast<std::size_t>(block_rows_));
    }
  }

  void read_rows(int y0, int rows, cv::Mat& out) override {
    for (int y = y0; y < y0 + rows;) {
      const int block = y / block_rows_;
      if (block != block_index_) decode_block(block);
      const int first = block * block_rows_;
      const int end = std::min(y0 + rows, first + block_.rows);
      block_.rowRange(y - first, end - first).copyTo(out.rowRange(y - y0, end - y0));
      y = end;
    }
  }

  void decode_block(int block) {
    const int first = block * block_rows_;
    const int rows = std::min(block_rows_, layout_.height - first);
    block_.create(rows, layout_.width, type());
    block_index_ = -1;
    const int planes = layout_.planar ? std::min(layout_.samples, layout_.channels) : 1;
    for (int plane = 0; plane < planes; ++plane) {
      if (tiled_) {
        for (int x0 = 0; x0 < layout_.width; x0 += tile_width_) {
          if (TIFFReadTile(file_->get(), buffer_.data(), static_cast<std::uint32_t>(x0),
                           static_cast<std::uint32_t>(first), 0, static_cast<std::uint16_t>(plane)) < 0)
            file_->fail_here(fmt::format("cannot read the tile at ({}, {})", x0, first));
          const int cols = std::min(tile_width_, layout_.width - x0);
          for (int r = 0; r < rows; ++r)
            copy_pixels(layout_, buffer_.data() + static_cast<std::size_t>(r) * unit_row_bytes_, cols, plane,
                        block_.ptr<std::uint8_t>(r) +
                            static_cast<std::size_t>(x0) * layout_.channels * layout_.bytes);
        }
      } else {
        const tstrip_t strips_per_plane =
            TIFFNumberOfStrips(file_->get()) / static_cast<tstrip_t>(layout_.planar ? layout_.samples : 1);
        const auto strip = static_cast<tstrip_t>(plane) * strips_per_plane + static_cast<tstrip_t>(block);
        const tmsize_t wanted = static_cast<tmsize_t>(unit_row_bytes_) * rows;
        if (static_cast<tstrip_t>(block) >= strips_per_plane ||
            TIFFReadEncodedStrip(file_->get(), strip, buffer_.data(), wanted) < wanted)
          file_->fail_here(fmt::format("cannot read rows {} to {}", first, first + rows - 1));
        for (int r = 0; r < rows; ++r)
          copy_pixels(layout_, buffer_.data() + static_cast<std::size_t>(r) * unit_row_bytes_, layout_.width,
                      plane, block_.ptr<std::uint8_t>(r));
      }
    }
    block_index_ = block;
  }

  std::unique_ptr<TiffFile> file_;
  Layout layout_;
  bool tiled_ = false;
  int tile_width_ = 0;
  int block_rows_ = 1;
  std::size_t unit_row_bytes_ = 0;  // bytes of one row of a strip or tile, as libtiff decodes it
  std::vector<std::uint8_t> buffer_;
  cv::Mat block_;
  int block_index_ = -1;
};

}  // namespace

bool is_tiff_file(const std::filesystem::path& path) {
  const std::string extension = lower_extension(path);
  return extension == ".tif" || extension == ".tiff";
}

cv::Mat read_tiff(const std::filesystem::path& path) {
  try {
    TiffRows rows(path);
    cv::Mat out;
    rows.read(0, rows.size().height, out);
    if (out.depth() == CV_32F && !cv::checkRange(out))
      fail("{}: float samples hold NaN or infinity", path.string());
    return out;
  } catch (const std::bad_alloc&) {
    fail("{}: too large to decode in the memory available", path.string());
  } catch (const cv::Exception& e) {
    fail("{}: cannot decode ({})", path.string(), e.what());
  }
}

std::unique_ptr<RowReader> open_tiff_rows(const std::filesystem::path& path) {
  try {
    return std::make_unique<TiffRows>(path);
  } catch (const std::bad_alloc&) {
    fail("{}: too large to decode in the memory available", path.string());
  }
}

cv::Size read_tiff_size(const std::filesystem::path& path) { return size_of(TiffFile(path)); }

}  // namespace lightstage::io
