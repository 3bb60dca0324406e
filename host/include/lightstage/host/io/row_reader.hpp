#pragma once
// An image's rows a band at a time, so that a stack larger than memory is
// decoded once, band by band (io/stack_bands.hpp), and never whole. The rows
// are what read_image gives for the same rows: same type, BGR order in memory,
// alpha dropped. PNG rows come through libpng, TIFF strips and tiles through
// libtiff (a strip or a row of tiles is decoded once and kept until the bands
// pass it), PFM rows by seeking to them. Camera RAW files and interlaced PNGs
// cannot be decoded in part: they are decoded whole when opened, their rows
// kept in an unlinked temporary file ($TMPDIR) and read back by band
// (decoded_whole() says so): disk, not memory, holds a stack of them. Each
// reader holds its file open.

#include <opencv2/core.hpp>

#include <cstddef>
#include <filesystem>
#include <memory>

namespace lightstage::io {

class RowReader {
 public:
  virtual ~RowReader() = default;
  RowReader(const RowReader&) = delete;
  RowReader& operator=(const RowReader&) = delete;

  const std::filesystem::path& path() const { return path_; }
  cv::Size size() const { return size_; }
  int type() const { return type_; }
  // True when the file is decoded whole rather than in bands (see above).
  virtual bool decoded_whole() const { return false; }

  // Rows [y0, y0 + rows) into `out`, reallocated to rows × width of type().
  // Bands read top to bottom decode the file once; a band above the last one
  // read starts the file's decoding again. Throws InputError naming the file
  // for rows outside the image or a file that fails to decode there (a
  // truncated or corrupt file is found only when its rows are reached).
  void read(int y0, int rows, cv::Mat& out);

 protected:
  RowReader(std::filesystem::path path, cv::Size size, int type);
  // Called with a checked, non-empty range and `out` already allocated.
  virtual void read_rows(int y0, int rows, cv::Mat& out) = 0;

 private:
  std::filesystem::path path_;
  cv::Size size_;
  int type_ = 0;
};

// How the caller reads: band after band, or one range of rows once (a file
// that decodes only whole then stays in memory: a temporary file would only
// be written and dropped).
enum class RowReading { kInBands, kOnce };

// Opens `path` (a stack image: PNG, PFM, TIFF or camera RAW, read_image's
// dispatch) and reads its header. Throws InputError naming the file when it
// is missing, not such an image, or of a type read_image refuses.
std::unique_ptr<RowReader> open_row_reader(const std::filesystem::path& path,
                                           RowReading reading = RowReading::kInBands);

}  // namespace lightstage::io
