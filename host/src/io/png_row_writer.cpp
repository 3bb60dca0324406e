// PNG rows through libpng, as write_png writes the whole image: 8- or 16-bit
// grey or colour (BGR in memory), 16-bit samples big-endian in the file.
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/row_writer.hpp"
#include "util/atomic_file.hpp"

#include <png.h>

#include <bit>
#include <csetjmp>
#include <cstdio>
#include <string>
#include <vector>

namespace lightstage::io {
namespace {

// libpng reports errors by longjmp and writes through a callback: the
// functions that call it hold no C++ object with a destructor between their
// setjmp and libpng's calls, and the callback only gathers bytes, which the
// writer hands to the file after libpng returns.
struct PngSink {
  std::string bytes;
  char error[256] = {};
};

void on_error(png_structp png, png_const_charp message) {
  auto* sink = static_cast<PngSink*>(png_get_error_ptr(png));
  std::snprintf(sink->error, sizeof sink->error, "%s", message);
  png_longjmp(png, 1);
}
void on_warning(png_structp, png_const_charp) {}
void on_write(png_structp png, png_bytep data, png_size_t length) {
  static_cast<PngSink*>(png_get_io_ptr(png))->bytes.append(reinterpret_cast<const char*>(data), length);
}
void on_flush(png_structp) {}

bool write_header(png_structp png, png_infop info, cv::Size size, int depth, int channels) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_IHDR(png, info, static_cast<png_uint_32>(size.width), static_cast<png_uint_32>(size.height),
               depth == CV_16U ? 16 : 8, channels == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_GRAY,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, 1);  // OpenCV's default: fast, most of the gain
  png_write_info(png, info);
  if (channels == 3) png_set_bgr(png);
  if (depth == CV_16U && std::endian::native == std::endian::little) png_set_swap(png);
  return true;
}

bool write_png_rows(png_structp png, png_bytepp rows, png_uint_32 count) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_write_rows(png, rows, count);
  return true;
}

bool write_png_end(png_structp png) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_write_end(png, nullptr);
  return true;
}

// libpng's write structures, released however the writer ends.
struct PngWriteStruct {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~PngWriteStruct() { png_destroy_write_struct(&png, &info); }
};

class PngRowWriter final : public RowWriter {
 public:
  PngRowWriter(const std::filesystem::path& path, cv::Size size, int type)
      : RowWriter(path, size, type), file_(path) {
    write_.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &sink_, on_error, on_warning);
    if (write_.png != nullptr) write_.info = png_create_info_struct(write_.png);
    if (write_.png == nullptr || write_.info == nullptr)
      fail("{}: cannot write as PNG: out of memory", path.string());
    png_set_write_fn(write_.png, &sink_, on_write, on_flush);
    if (!write_header(write_.png, write_.info, size, CV_MAT_DEPTH(type), CV_MAT_CN(type))) fail_png();
    flush();
  }

 private:
  void write_rows(const cv::Mat& rows, int) override {
    std::vector<png_bytep> pointers(static_cast<std::size_t>(rows.rows));
    for (int r = 0; r < rows.rows; ++r)
      pointers[static_cast<std::size_t>(r)] = const_cast<png_bytep>(rows.ptr(r));
    if (!write_png_rows(write_.png, pointers.data(), static_cast<png_uint_32>(rows.rows))) fail_png();
    flush();
  }
  void finish() override {
    if (!write_png_end(write_.png)) fail_png();
    flush();
    file_.commit();
  }
  void flush() {
    file_.append(sink_.bytes);
    sink_.bytes.clear();
  }
  [[noreturn]] void fail_png() const { fail("{}: cannot write as PNG: {}", path().string(), sink_.error); }

  util::TemporaryFile file_;
  PngSink sink_;
  PngWriteStruct write_;
};

}  // namespace

std::unique_ptr<RowWriter> open_png_writer(const std::filesystem::path& path, cv::Size size, int type) {
  const int depth = CV_MAT_DEPTH(type), channels = CV_MAT_CN(type);
  if ((depth != CV_8U && depth != CV_16U) || (channels != 1 && channels != 3))
    fail("{}: cannot write as PNG: {}; expected 8- or 16-bit with 1 or 3 channels", path.string(),
         cv::typeToString(type));
  return std::make_unique<PngRowWriter>(path, size, type);
}

}  // namespace lightstage::io
