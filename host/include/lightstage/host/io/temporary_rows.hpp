#pragma once
// Rows of an image kept on disk instead of in memory: an unlinked file in the
// temporary folder ($TMPDIR, default /tmp), gone with its descriptor however
// the process ends. Rows are appended top to bottom, a band at a time, and read
// back by band in any order. Holds what a second pass over decoded rows needs
// without decoding them again (a camera RAW frame's rows, the intensity
// calibration's target).

#include <opencv2/core.hpp>

#include <cstddef>
#include <string>

namespace lightstage::io {

class TemporaryRows {
 public:
  // Rows `width` wide of OpenCV `type`, `rows` of them expected (for the room errors ask for); `what`
  // names them in errors (the file they came from). Throws InputError naming $TMPDIR when no temporary
  // file can be made.
  TemporaryRows(std::string what, int width, int type, int rows);
  ~TemporaryRows();
  TemporaryRows(const TemporaryRows&) = delete;
  TemporaryRows& operator=(const TemporaryRows&) = delete;

  // Appends `rows` (width × any height, of the type above) below the last. Throws InputError naming the
  // data and $TMPDIR when the folder has no room.
  void append(const cv::Mat& rows);
  // Rows [y0, y0 + count) of those appended, into `out` (reallocated).
  void read(int y0, int count, cv::Mat& out) const;
  int rows() const { return rows_; }

 private:
  [[noreturn]] void refuse(const char* step) const;

  std::string what_;
  int width_, type_;
  std::size_t row_bytes_;
  int expected_rows_;
  int rows_ = 0;
  int fd_ = -1;
};

}  // namespace lightstage::io
