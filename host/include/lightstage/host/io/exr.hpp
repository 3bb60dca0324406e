#pragma once
// OpenEXR float images, read and written through OpenEXR's own library (not
// OpenCV's codec, which hides the channel names and needs an environment
// switch). A single-part flat image, scan-line or tiled; channels are named
// (e.g. Y, Z or R for one channel; R, G, B for colour), and a cv::Mat's
// channel i is the i-th name of the list given: the order is the caller's
// (OpenCV's BGR images pass {"B", "G", "R"}).

#include <opencv2/core.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace lightstage::io {

enum class ExrPixelType { kUint32, kHalf, kFloat32 };

const char* to_string(ExrPixelType type);

struct ExrChannel {
  std::string name;
  ExrPixelType type = ExrPixelType::kFloat32;
  int x_sampling = 1, y_sampling = 1;
};

// What the header says, known before any pixel is decoded.
struct ExrHeader {
  std::vector<ExrChannel> channels;  // in the file's order (sorted by name)
  cv::Size size;                     // of the data window
  bool cropped = false;              // the data window differs from the display window
  bool tiled = false;
};

// Images up to this many pixels, each side at most kExrMaxSide: the header
// alone decides what is allocated, so a few bytes must not ask for gigabytes.
inline constexpr std::int64_t kExrMaxPixels = std::int64_t{1} << 26;
inline constexpr int kExrMaxSide = 1 << 16;

// An EXR file held in memory, its header parsed when opened. One read() at a
// time: the reads share the in-memory stream's position.
class ExrFile {
 public:
  // Throws InputError naming the file: unreadable, not an EXR, an unsupported
  // version, deep or multi-part, a truncated or malformed header, an image
  // larger than the limits above.
  explicit ExrFile(const std::filesystem::path& path);
  // The same for bytes already in memory; `name` stands for the file in messages.
  ExrFile(std::string bytes, std::string name);
  ~ExrFile();
  ExrFile(ExrFile&&) noexcept;
  ExrFile& operator=(ExrFile&&) noexcept;

  const ExrHeader& header() const { return header_; }
  const std::string& name() const { return name_; }

  // The named channels (1 to 4), in that order, as CV_32FC(n) of header().size:
  // HALF and UINT widen to float; NaN and infinities are passed through.
  // Throws InputError naming the file when a channel is missing, repeated or
  // subsampled, the image is cropped, or the pixels cannot be decoded.
  cv::Mat read(const std::vector<std::string>& channels) const;

 private:
  struct Bytes;
  void parse_header();

  std::string name_;
  std::unique_ptr<Bytes> bytes_;
  ExrHeader header_;
};

// ExrFile(path).read(channels).
cv::Mat read_exr(const std::filesystem::path& path, const std::vector<std::string>& channels);

class RowReader;
// The named channels read a band of rows at a time (row_reader.hpp), decoded
// from the file on disk as the rows are asked for: never held whole, so only
// the per-side limit applies, not kExrMaxPixels. The channel checks and
// errors of ExrFile::read; a file that does not decode at some rows is found
// when they are read.
std::unique_ptr<RowReader> open_exr_rows(const std::filesystem::path& path,
                                         const std::vector<std::string>& channels);

// Writes CV_32FC1 or CV_32FC3 as 32-bit FLOAT channels, uncompressed,
// atomically (a temporary file beside it, then a rename); channel i of the
// image is named channels[i]. Throws InputError naming the file for another
// type, names that do not match the channels (wrong count, empty, repeated),
// or a write error.
void write_exr(const std::filesystem::path& path, const cv::Mat& image,
               const std::vector<std::string>& channels);

}  // namespace lightstage::io
