#include "lightstage/host/io/pfm.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/row_writer.hpp"
#include "util/atomic_file.hpp"

#include <fmt/format.h>
#include <opencv2/core.hpp>

#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace lightstage::io {
namespace {

// Reads the next whitespace-delimited header token; a token that runs into
// the end of `data` may be cut (only the file's first bytes were read).
bool next_token(std::string_view data, std::size_t& pos, std::string_view& token) {
  while (pos < data.size() && std::isspace(static_cast<unsigned char>(data[pos]))) ++pos;
  const std::size_t start = pos;
  while (pos < data.size() && !std::isspace(static_cast<unsigned char>(data[pos]))) ++pos;
  token = data.substr(start, pos - start);
  return !token.empty() && pos < data.size();
}

// Parses the whole token as a number.
template <typename T>
bool parse_whole(std::string_view token, T& value) {
  const char* begin = token.data();
  const char* end = begin + token.size();
  const auto [next, error] = std::from_chars(begin, end, value);
  return error == std::errc() && next == end;
}

std::uint32_t byte_swap(std::uint32_t v) {
  return ((v & 0xffu) << 24) | ((v & 0xff00u) << 8) | ((v >> 8) & 0xff00u) | (v >> 24);
}

}  // namespace

PfmHeader parse_pfm_header(const std::filesystem::path& path, std::string_view bytes) {
  std::size_t pos = 0;
  std::string_view magic, width_text, height_text, scale_text;
  if (!next_token(bytes, pos, magic) || (magic != "PF" && magic != "Pf")) {
    fail("{}: not a PFM file (expected 'PF' or 'Pf' at the start)", path.string());
  }
  if (!next_token(bytes, pos, width_text) || !next_token(bytes, pos, height_text) ||
      !next_token(bytes, pos, scale_text)) {
    fail("{}: truncated PFM header", path.string());
  }
  PfmHeader header;
  double scale = 0;
  if (!parse_whole(width_text, header.width) || !parse_whole(height_text, header.height) ||
      !parse_whole(scale_text, scale)) {
    fail("{}: malformed PFM header '{} {} {}'", path.string(), width_text.substr(0, 20),
         height_text.substr(0, 20), scale_text.substr(0, 20));
  }
  if (header.width <= 0 || header.height <= 0 || header.width > 1 << 16 || header.height > 1 << 16) {
    fail("{}: bad PFM size {}x{}", path.string(), header.width, header.height);
  }
  if (scale == 0 || !std::isfinite(scale)) fail("{}: bad PFM scale '{}'", path.string(), scale_text);
  header.channels = magic == "PF" ? 3 : 1;
  header.little_endian = scale < 0;
  header.data_offset = pos + 1;  // exactly one whitespace character ends the header
  return header;
}

cv::Mat read_pfm(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("{}: cannot open (no such file or not readable)", path.string());
  const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());

  const PfmHeader header = parse_pfm_header(path, data);
  const int width = header.width, height = header.height, channels = header.channels;
  const std::size_t pos = header.data_offset;
  const std::size_t row_values = static_cast<std::size_t>(width) * static_cast<std::size_t>(channels);
  const std::size_t bytes = row_values * static_cast<std::size_t>(height) * sizeof(float);
  if (pos > data.size() || data.size() - pos < bytes) {
    fail("{}: truncated PFM data ({} bytes, expected {})", path.string(),
         pos > data.size() ? 0 : data.size() - pos, bytes);
  }
  const bool file_little = header.little_endian;
  const bool swap = file_little != (std::endian::native == std::endian::little);

  cv::Mat image(height, width, CV_MAKETYPE(CV_32F, channels));
  std::vector<std::uint32_t> row(row_values);
  for (int file_row = 0; file_row < height; ++file_row) {
    std::memcpy(row.data(),
                data.data() + pos + static_cast<std::size_t>(file_row) * row_values * sizeof(float),
                row_values * sizeof(float));
    if (swap) {
      for (auto& v : row) v = byte_swap(v);
    }
    // Rows are stored bottom-to-top; channels are RGB on disk, BGR in memory.
    auto* out = image.ptr<float>(height - 1 - file_row);
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < channels; ++c) {
        const int disk_channel = channels == 3 ? 2 - c : 0;
        out[x * channels + c] =
            std::bit_cast<float>(row[static_cast<std::size_t>(x * channels + disk_channel)]);
      }
    }
  }
  return image;
}

namespace {

// PFM stores rows bottom to top: each band goes where its rows belong.
class PfmRowWriter final : public RowWriter {
 public:
  PfmRowWriter(const std::filesystem::path& path, cv::Size size, int type)
      : RowWriter(path, size, type), file_(path), channels_(CV_MAT_CN(type)) {
    const std::string header =
        fmt::format("{}\n{} {}\n-1\n", channels_ == 3 ? "PF" : "Pf", size.width, size.height);
    header_ = header.size();
    file_.append(header);
  }

 private:
  void write_rows(const cv::Mat& rows, int y0) override {
    const auto values = static_cast<std::size_t>(size().width) * static_cast<std::size_t>(channels_);
    std::vector<float> out(values * static_cast<std::size_t>(rows.rows));
    // File rows (bottom up) height-1-(y0+rows-1) .. height-1-y0: one contiguous run, last band row first.
    for (int r = 0; r < rows.rows; ++r) {
      const float* in = rows.ptr<float>(rows.rows - 1 - r);
      float* row = out.data() + static_cast<std::size_t>(r) * values;
      for (int x = 0; x < size().width; ++x)
        for (int c = 0; c < channels_; ++c)
          row[x * channels_ + c] = in[x * channels_ + (channels_ == 3 ? 2 - c : 0)];
    }
    if constexpr (std::endian::native != std::endian::little) {
      for (float& v : out) v = std::bit_cast<float>(byte_swap(std::bit_cast<std::uint32_t>(v)));
    }
    const auto first_file_row = static_cast<std::uint64_t>(size().height - (y0 + rows.rows));
    file_.write_at(header_ + first_file_row * values * sizeof(float),
                   std::string_view(reinterpret_cast<const char*>(out.data()), out.size() * sizeof(float)));
  }
  void finish() override { file_.commit(); }

  util::TemporaryFile file_;
  int channels_;
  std::uint64_t header_ = 0;
};

}  // namespace

std::unique_ptr<RowWriter> open_pfm_writer(const std::filesystem::path& path, cv::Size size, int type) {
  if (type != CV_32FC1 && type != CV_32FC3)
    fail("{}: cannot write as PFM: expected CV_32FC1 or CV_32FC3, got {}", path.string(),
         cv::typeToString(type));
  return std::make_unique<PfmRowWriter>(path, size, type);
}

void write_pfm(const std::filesystem::path& path, const cv::Mat& image) {
  const auto writer = open_pfm_writer(path, image.size(), image.type());
  writer->write(image);
  writer->commit();
}

}  // namespace lightstage::io
