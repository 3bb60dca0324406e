#include "lightstage/host/io/jpeg_image.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "util/atomic_file.hpp"

#include <cstdio>  // before jpeglib.h, which needs FILE and size_t declared

#include <jerror.h>
#include <jpeglib.h>

#include <csetjmp>
#include <fstream>
#include <iterator>
#include <new>
#include <string>
#include <utility>
#include <vector>

#ifndef JCS_EXTENSIONS
#error "libjpeg-turbo's JCS_EXT_BGR is needed (Debian's libjpeg62-turbo-dev)"
#endif

namespace lightstage::io {
namespace {

// libjpeg reports errors by longjmp: the functions that call it hold no C++
// object with a destructor between their setjmp and libjpeg's calls.
struct JpegErrors {
  jpeg_error_mgr manager;  // first: libjpeg hands back &manager as the struct's err
  std::jmp_buf jump;
  char text[JMSG_LENGTH_MAX] = {};
  char first_warning[JMSG_LENGTH_MAX] = {};
};

[[noreturn]] void on_error(j_common_ptr info) {
  auto* errors = reinterpret_cast<JpegErrors*>(info->err);
  info->err->format_message(info, errors->text);
  std::longjmp(errors->jump, 1);
}

// Data that ends before the image does, which libjpeg would pad with grey
// rows, is an error; the first other warning (corrupt data libjpeg skipped) is
// kept to be logged.
void on_message(j_common_ptr info, int level) {
  if (level >= 0) return;  // trace messages
  if (info->err->msg_code == JWRN_JPEG_EOF) on_error(info);
  auto* errors = reinterpret_cast<JpegErrors*>(info->err);
  if (errors->first_warning[0] == '\0') info->err->format_message(info, errors->first_warning);
}

void route_errors(jpeg_error_mgr* manager) {
  jpeg_std_error(manager);
  manager->error_exit = on_error;
  manager->emit_message = on_message;
}

struct Decompressor {
  jpeg_decompress_struct info{};
  JpegErrors errors{};
  bool created = false;
  ~Decompressor() {
    if (created) jpeg_destroy_decompress(&info);
  }
};

bool create(Decompressor* d) {
  route_errors(&d->errors.manager);
  d->info.err = &d->errors.manager;
  if (setjmp(d->errors.jump)) return false;
  jpeg_create_decompress(&d->info);
  d->created = true;
  return true;
}

bool read_header(Decompressor* d, const std::uint8_t* data, std::size_t size) {
  if (setjmp(d->errors.jump)) return false;
  jpeg_mem_src(&d->info, data, static_cast<unsigned long>(size));
  jpeg_read_header(&d->info, TRUE);
  return true;
}

bool start(Decompressor* d, J_COLOR_SPACE out) {
  if (setjmp(d->errors.jump)) return false;
  d->info.out_color_space = out;
  jpeg_start_decompress(&d->info);
  return true;
}

bool read_lines(Decompressor* d, JSAMPARRAY rows) {
  if (setjmp(d->errors.jump)) return false;
  while (d->info.output_scanline < d->info.output_height) {
    const JDIMENSION y = d->info.output_scanline;
    jpeg_read_scanlines(&d->info, rows + y, d->info.output_height - y);
  }
  jpeg_finish_decompress(&d->info);
  return true;
}

// The compressed bytes, appended to a string a buffer at a time (libjpeg's
// own memory destination frees buffers it has outgrown behind its caller's back).
struct StringDestination {
  jpeg_destination_mgr manager{};  // first: libjpeg hands back &manager as the struct's dest
  std::string bytes;
  bool out_of_memory = false;
  JOCTET buffer[16384] = {};
};

StringDestination& destination(j_compress_ptr info) {
  return *reinterpret_cast<StringDestination*>(info->dest);
}

void keep(StringDestination& d, std::size_t count) {
  try {
    d.bytes.append(reinterpret_cast<const char*>(d.buffer), count);
  } catch (const std::bad_alloc&) {
    d.out_of_memory = true;  // no exception may pass through libjpeg
  }
  d.manager.next_output_byte = d.buffer;
  d.manager.free_in_buffer = sizeof d.buffer;
}

void start_destination(j_compress_ptr info) { keep(destination(info), 0); }
boolean empty_destination(j_compress_ptr info) {
  keep(destination(info), sizeof destination(info).buffer);
  return TRUE;
}
void end_destination(j_compress_ptr info) {
  StringDestination& d = destination(info);
  keep(d, sizeof d.buffer - d.manager.free_in_buffer);
}

struct Compressor {
  jpeg_compress_struct info{};
  JpegErrors errors{};
  StringDestination out;
  bool created = false;
  ~Compressor() {
    if (created) jpeg_destroy_compress(&info);
  }
};

bool create(Compressor* c) {
  route_errors(&c->errors.manager);
  c->info.err = &c->errors.manager;
  if (setjmp(c->errors.jump)) return false;
  jpeg_create_compress(&c->info);
  c->created = true;
  return true;
}

bool compress(Compressor* c, const cv::Mat* image, int quality) {
  if (setjmp(c->errors.jump)) return false;
  c->out.manager.init_destination = start_destination;
  c->out.manager.empty_output_buffer = empty_destination;
  c->out.manager.term_destination = end_destination;
  c->info.dest = &c->out.manager;
  c->info.image_width = static_cast<JDIMENSION>(image->cols);
  c->info.image_height = static_cast<JDIMENSION>(image->rows);
  c->info.input_components = image->channels();
  c->info.in_color_space = image->channels() == 3 ? JCS_EXT_BGR : JCS_GRAYSCALE;
  jpeg_set_defaults(&c->info);
  jpeg_set_quality(&c->info, quality, TRUE);
  jpeg_start_compress(&c->info, TRUE);
  while (c->info.next_scanline < c->info.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(image->ptr<JSAMPLE>(static_cast<int>(c->info.next_scanline)));
    jpeg_write_scanlines(&c->info, &row, 1);
  }
  jpeg_finish_compress(&c->info);
  return true;
}

std::vector<std::uint8_t> read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("{}: cannot open (no such file or not readable)", path.string());
  std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) fail("{}: cannot read", path.string());
  return bytes;
}

// The header read and checked: a size this reads, and colours it decodes.
void start_reading(Decompressor& d, std::span<const std::uint8_t> bytes, std::string_view name) {
  if (!create(&d)) fail("{}: cannot start the JPEG decoder ({})", name, d.errors.text);
  if (!read_header(&d, bytes.data(), bytes.size())) fail("{}: not a readable JPEG ({})", name, d.errors.text);
  const jpeg_decompress_struct& info = d.info;
  if (info.jpeg_color_space == JCS_CMYK || info.jpeg_color_space == JCS_YCCK)
    fail("{}: a CMYK JPEG (made for print), not a camera's image", name);
  if (info.image_width > kMaxImageSide || info.image_height > kMaxImageSide)
    fail("{}: JPEG of {}x{} pixels, larger than the {} a side this reads", name, info.image_width,
         info.image_height, kMaxImageSide);
}

}  // namespace

bool is_jpeg_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char head[3] = {};
  in.read(reinterpret_cast<char*>(head), sizeof head);
  return in.gcount() == 3 && head[0] == 0xFF && head[1] == 0xD8 && head[2] == 0xFF;
}

cv::Mat decode_jpeg(std::span<const std::uint8_t> bytes, std::string_view name) {
  Decompressor d;
  start_reading(d, bytes, name);
  const jpeg_decompress_struct& info = d.info;
  const bool grey = info.num_components == 1;
  if (!start(&d, grey ? JCS_GRAYSCALE : JCS_EXT_BGR)) fail("{}: cannot decode ({})", name, d.errors.text);
  cv::Mat image(static_cast<int>(info.output_height), static_cast<int>(info.output_width),
                grey ? CV_8UC1 : CV_8UC3);
  std::vector<JSAMPROW> rows(static_cast<std::size_t>(image.rows));
  for (int y = 0; y < image.rows; ++y) rows[static_cast<std::size_t>(y)] = image.ptr<JSAMPLE>(y);
  if (!read_lines(&d, rows.data())) fail("{}: cannot decode ({})", name, d.errors.text);
  if (d.errors.first_warning[0] != '\0')
    logger("host")->warn("{}: {} (decoded as libjpeg repaired it)", name, d.errors.first_warning);
  return image;
}

cv::Mat read_jpeg(const std::filesystem::path& path) { return decode_jpeg(read_file(path), path.string()); }

cv::Size read_jpeg_size(const std::filesystem::path& path) {
  const std::vector<std::uint8_t> bytes = read_file(path);
  Decompressor d;
  start_reading(d, bytes, path.string());
  return {static_cast<int>(d.info.image_width), static_cast<int>(d.info.image_height)};
}

std::string encode_jpeg(const cv::Mat& image, int quality, std::string_view name) {
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3))
    fail("{}: cannot write as JPEG: {}; expected 8-bit with 1 or 3 channels", name,
         cv::typeToString(image.type()));
  if (quality < 1 || quality > 100) fail("{}: JPEG quality {} (1 to 100)", name, quality);
  Compressor c;
  if (!create(&c) || !compress(&c, &image, quality))
    fail("{}: cannot write as JPEG ({})", name, c.errors.text);
  if (c.out.out_of_memory) fail("{}: cannot write as JPEG (out of memory)", name);
  return std::move(c.out.bytes);
}

void write_jpeg(const std::filesystem::path& path, const cv::Mat& image, int quality) {
  util::commit_temporary(util::write_temporary(path, encode_jpeg(image, quality, path.string())), path);
}

}  // namespace lightstage::io
