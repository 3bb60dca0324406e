#include "lightstage/host/io/row_reader.hpp"

#include "io/file_extension.hpp"
#include "io/row_readers.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/huge_pages.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/raw_image.hpp"
#include "lightstage/host/io/tiff_image.hpp"

#include <bit>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace lightstage::io {
namespace {

// PFM rows lie bottom to top at fixed offsets: each band is read where it lies.
class PfmRows final : public RowReader {
 public:
  PfmRows(const std::filesystem::path& path, const PfmHeader& header)
      : RowReader(path, {header.width, header.height}, CV_MAKETYPE(CV_32F, header.channels)),
        header_(header),
        in_(path, std::ios::binary) {
    if (!in_) fail("{}: cannot open (no such file or not readable)", path.string());
    const std::uintmax_t needed =
        header.data_offset + row_bytes() * static_cast<std::uintmax_t>(header.height);
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(path, error);
    if (error || size < needed)
      fail("{}: truncated PFM data ({} bytes, expected {})", path.string(), error ? 0 : size, needed);
  }

 private:
  std::size_t row_bytes() const {
    return static_cast<std::size_t>(header_.width) * static_cast<std::size_t>(header_.channels) *
           sizeof(float);
  }

  void read_rows(int y0, int rows, cv::Mat& out) override {
    // The band's rows are contiguous on disk, bottom row first.
    const int first_file_row = header_.height - (y0 + rows);
    std::vector<std::uint32_t> data(row_bytes() / sizeof(float) * static_cast<std::size_t>(rows));
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(header_.data_offset +
                                          static_cast<std::size_t>(first_file_row) * row_bytes()));
    in_.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(data.size() * sizeof(float)));
    if (!in_) fail("{}: cannot read rows {} to {}", path().string(), y0, y0 + rows - 1);
    const bool swap = header_.little_endian != (std::endian::native == std::endian::little);
    const int channels = header_.channels;
    const std::size_t values = row_bytes() / sizeof(float);
    for (int r = 0; r < rows; ++r) {
      const std::uint32_t* in = data.data() + static_cast<std::size_t>(rows - 1 - r) * values;
      auto* row = out.ptr<float>(r);
      for (int x = 0; x < header_.width; ++x) {
        for (int c = 0; c < channels; ++c) {
          std::uint32_t v = in[static_cast<std::size_t>(x * channels + (channels == 3 ? 2 - c : 0))];
          if (swap) v = __builtin_bswap32(v);
          row[x * channels + c] = std::bit_cast<float>(v);
        }
      }
    }
  }

  PfmHeader header_;
  std::ifstream in_;
};

// A file decoded whole for a single read: held until the reader goes.
class DecodedRows final : public RowReader {
 public:
  DecodedRows(const std::filesystem::path& path, cv::Mat image)
      : RowReader(path, image.size(), image.type()), image_(std::move(image)) {}
  bool decoded_whole() const override { return true; }

 private:
  void read_rows(int y0, int rows, cv::Mat& out) override { image_.rowRange(y0, y0 + rows).copyTo(out); }

  cv::Mat image_;
};

std::unique_ptr<RowReader> open_pfm_rows(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("{}: cannot open (no such file or not readable)", path.string());
  std::string head(256, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  return std::make_unique<PfmRows>(path, parse_pfm_header(path, head));
}

}  // namespace

RowReader::RowReader(std::filesystem::path path, cv::Size size, int type)
    : path_(std::move(path)), size_(size), type_(type) {}

void RowReader::read(int y0, int rows, cv::Mat& out) {
  if (rows <= 0 || y0 < 0 || y0 > size_.height - rows)
    fail("{}: rows {} to {} are outside its {} rows", path_.string(), y0,
         static_cast<std::int64_t>(y0) + rows - 1, size_.height);
  out.create(rows, size_.width, type_);
  advise_huge_pages(out.data, out.total() * out.elemSize());  // every band's frames are written afresh
  read_rows(y0, rows, out);
}

std::unique_ptr<RowReader> open_row_reader(const std::filesystem::path& path, RowReading reading) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) fail("{}: no such file", path.string());
  if (!std::filesystem::is_regular_file(path, error)) fail("{}: not a regular file", path.string());
  if (lower_extension(path) == ".pfm") return open_pfm_rows(path);
  if (is_tiff_file(path)) return open_tiff_rows(path);
  if (!is_raw_file(path)) {
    if (auto png = open_png_rows(path)) return png;
  }
  if (reading == RowReading::kOnce) return std::make_unique<DecodedRows>(path, read_image(path));
  return spill_decoded_rows(path, read_image(path));
}

}  // namespace lightstage::io
