// PNG through libpng, a band of rows at a time or (read_png) the whole image,
// transformed as OpenCV's imread(IMREAD_UNCHANGED) and read_image did before
// (so the pixels are the same): 1-, 2- and 4-bit grey widened to 8 bits,
// palettes expanded to RGB, grey with alpha made RGB, alpha dropped, colour in
// BGR order, 16-bit samples in the machine's byte order.
#include "io/row_readers.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/huge_pages.hpp"
#include "lightstage/host/io/stack_io.hpp"

#include <png.h>

#include <bit>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace lightstage::io {
namespace {

// libpng reports errors by longjmp; the functions that call it hold no C++
// object with a destructor between their setjmp and libpng's calls.
struct PngErrorText {
  char text[256] = {};
};

void on_png_error(png_structp png, png_const_charp message) {
  auto* error = static_cast<PngErrorText*>(png_get_error_ptr(png));
  std::snprintf(error->text, sizeof error->text, "%s", message);
  png_longjmp(png, 1);
}
void on_png_warning(png_structp, png_const_charp) {}

struct PngLayout {
  png_uint_32 width = 0, height = 0;
  int channels = 1;  // after the transforms: 1 (grey) or 3 (BGR)
  int bit_depth = 8;
  bool interlaced = false;    // then libpng hands out rows only whole-image (png_read_image)
  std::size_t row_bytes = 0;  // as libpng delivers a transformed row
};

bool read_png_header(png_structp png, png_infop info, std::FILE* file, PngLayout* layout) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_init_io(png, file);
  png_read_info(png, info);
  int bit_depth = 0, colour = 0, interlace = 0;
  png_get_IHDR(png, info, &layout->width, &layout->height, &bit_depth, &colour, &interlace, nullptr, nullptr);
  layout->interlaced = interlace != PNG_INTERLACE_NONE;
  layout->bit_depth = bit_depth == 16 ? 16 : 8;
  const bool colour_or_alpha = (colour & (PNG_COLOR_MASK_COLOR | PNG_COLOR_MASK_ALPHA)) != 0;
  layout->channels = colour_or_alpha ? 3 : 1;
  if (colour == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if ((colour & PNG_COLOR_MASK_COLOR) == 0 && bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (colour == PNG_COLOR_TYPE_GRAY_ALPHA) png_set_gray_to_rgb(png);
  png_set_strip_alpha(png);
  if (layout->channels == 3) png_set_bgr(png);
  if (bit_depth == 16 && std::endian::native == std::endian::little) png_set_swap(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  layout->row_bytes = png_get_rowbytes(png, info);
  return true;
}

bool read_png_rows(png_structp png, png_bytep* rows, int count) {
  if (setjmp(png_jmpbuf(png))) return false;
  for (int i = 0; i < count; ++i) png_read_row(png, rows[i], nullptr);
  return true;
}

bool read_png_image(png_structp png, png_bytep* rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_image(png, rows);
  return true;
}

// The chunks after the image data, to its end (a file cut after its last row is refused, as read_image
// refuses it).
bool read_png_end(png_structp png) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_end(png, nullptr);
  return true;
}

class PngFile {
 public:
  explicit PngFile(const std::filesystem::path& path) : path_(path) {
    file_ = std::fopen(path.c_str(), "rb");
    if (file_ == nullptr) fail("{}: cannot open (no such file or not readable)", path.string());
    png_ = png_create_read_struct(PNG_LIBPNG_VER_STRING, &error_, on_png_error, on_png_warning);
    if (png_ != nullptr) info_ = png_create_info_struct(png_);
    if (png_ == nullptr || info_ == nullptr) {
      close();
      fail("{}: cannot start the PNG decoder (out of memory)", path.string());
    }
    if (!read_png_header(png_, info_, file_, &layout_)) {
      const std::string message = error_.text;
      close();
      fail("{}: not a readable PNG ({})", path.string(), message);
    }
    const std::size_t expected =
        static_cast<std::size_t>(layout_.width) * layout_.channels * layout_.bit_depth / 8;
    if (layout_.width == 0 || layout_.height == 0 || layout_.width > kMaxImageSide ||
        layout_.height > kMaxImageSide || layout_.row_bytes != expected) {
      close();
      fail("{}: a PNG of {}x{} pixels, {} bytes a row (each side 1 to {}, {} bytes expected)", path.string(),
           layout_.width, layout_.height, layout_.row_bytes, kMaxImageSide, expected);
    }
  }
  ~PngFile() { close(); }
  PngFile(const PngFile&) = delete;
  PngFile& operator=(const PngFile&) = delete;

  const PngLayout& layout() const { return layout_; }
  int next_row() const { return next_row_; }

  // Throws InputError naming the file; the decoder is then unusable (libpng's state after an error is not).
  void read(int count, std::vector<png_bytep>& rows) {
    if (!read_png_rows(png_, rows.data(), count))
      fail("{}: cannot decode rows {} to {} ({})", path_.string(), next_row_, next_row_ + count - 1,
           error_.text);
    next_row_ += count;
    if (next_row_ == static_cast<int>(layout_.height)) read_end();
  }

  // Every row at once, interlaced or not.
  void read_whole(std::vector<png_bytep>& rows) {
    if (!read_png_image(png_, rows.data())) fail("{}: cannot decode ({})", path_.string(), error_.text);
    next_row_ = static_cast<int>(layout_.height);
    read_end();
  }

 private:
  void read_end() {
    if (!read_png_end(png_)) fail("{}: cannot decode the end of the file ({})", path_.string(), error_.text);
  }

  void close() {
    if (png_ != nullptr) png_destroy_read_struct(&png_, info_ != nullptr ? &info_ : nullptr, nullptr);
    if (file_ != nullptr) std::fclose(file_);
    png_ = nullptr;
    info_ = nullptr;
    file_ = nullptr;
  }

  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  png_structp png_ = nullptr;
  png_infop info_ = nullptr;
  PngErrorText error_;
  PngLayout layout_;
  int next_row_ = 0;
};

class PngRows final : public RowReader {
 public:
  PngRows(const std::filesystem::path& path, std::unique_ptr<PngFile> file)
      : RowReader(path, {static_cast<int>(file->layout().width), static_cast<int>(file->layout().height)},
                  CV_MAKETYPE(file->layout().bit_depth == 16 ? CV_16U : CV_8U, file->layout().channels)),
        file_(std::move(file)) {}

 private:
  void read_rows(int y0, int rows, cv::Mat& out) override {
    if (!file_ || y0 < file_->next_row()) file_ = std::make_unique<PngFile>(path());
    try {
      if (y0 > file_->next_row()) {
        // Rows above the band are decoded into one scratch row and dropped.
        std::vector<std::uint8_t> scratch(out.step[0]);
        std::vector<png_bytep> pointers{scratch.data()};
        while (file_->next_row() < y0) file_->read(1, pointers);
      }
      std::vector<png_bytep> pointers(static_cast<std::size_t>(rows));
      for (int r = 0; r < rows; ++r) pointers[static_cast<std::size_t>(r)] = out.ptr<png_byte>(r);
      file_->read(rows, pointers);
    } catch (...) {
      file_.reset();  // a later read starts the file again
      throw;
    }
  }

  std::unique_ptr<PngFile> file_;
};

}  // namespace

cv::Mat read_png(const std::filesystem::path& path) {
  PngFile file(path);
  const PngLayout& layout = file.layout();
  cv::Mat image(static_cast<int>(layout.height), static_cast<int>(layout.width),
                CV_MAKETYPE(layout.bit_depth == 16 ? CV_16U : CV_8U, layout.channels));
  advise_huge_pages(image.data, image.total() * image.elemSize());  // a stack's frames are most of its memory
  std::vector<png_bytep> rows(static_cast<std::size_t>(image.rows));
  for (int y = 0; y < image.rows; ++y) rows[static_cast<std::size_t>(y)] = image.ptr<png_byte>(y);
  file.read_whole(rows);
  return image;
}

std::unique_ptr<RowReader> open_png_rows(const std::filesystem::path& path) {
  auto file = std::make_unique<PngFile>(path);
  if (file->layout().interlaced) return nullptr;
  return std::make_unique<PngRows>(path, std::move(file));
}

}  // namespace lightstage::io
