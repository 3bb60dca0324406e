#pragma once
// An image written a band of rows at a time, top to bottom, so that a result
// larger than memory is never held whole (the mirror of row_reader.hpp). The
// rows go to a temporary sibling of the file as they come; commit() after the
// last row renames it into place, and a writer destroyed before that removes
// it: a reader never sees half an image. The files are what the whole-image
// writers make of the same pixels (write_png, write_pfm, write_exr).

#include <opencv2/core.hpp>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace lightstage::io {

class RowWriter {
 public:
  virtual ~RowWriter() = default;
  RowWriter(const RowWriter&) = delete;
  RowWriter& operator=(const RowWriter&) = delete;

  const std::filesystem::path& path() const { return path_; }
  cv::Size size() const { return size_; }
  int type() const { return type_; }
  int rows_written() const { return next_row_; }

  // The next rows.rows rows (of type() and size().width). Throws InputError
  // naming the file for another type or width, rows past the last, or a
  // failed write (Error for a full disk, as util::write_temporary).
  void write(const cv::Mat& rows);
  // After the last row: the file appears at path().
  void commit();

 protected:
  RowWriter(std::filesystem::path path, cv::Size size, int type);
  // Called with checked rows [y0, y0 + rows.rows), contiguous or not.
  virtual void write_rows(const cv::Mat& rows, int y0) = 0;
  virtual void finish() = 0;

 private:
  std::filesystem::path path_;
  cv::Size size_;
  int type_ = 0;
  int next_row_ = 0;
};

// 8- or 16-bit, 1, 3 or 4 channels (BGR or BGRA in memory, as write_png and encode_png).
std::unique_ptr<RowWriter> open_png_writer(const std::filesystem::path& path, cv::Size size, int type);
// CV_32FC1 or CV_32FC3 (BGR in memory, as write_pfm).
std::unique_ptr<RowWriter> open_pfm_writer(const std::filesystem::path& path, cv::Size size, int type);
// CV_32FC1 or CV_32FC3 with one name per channel in memory order (as write_exr: float, uncompressed).
std::unique_ptr<RowWriter> open_exr_writer(const std::filesystem::path& path, cv::Size size, int type,
                                           const std::vector<std::string>& channels);

}  // namespace lightstage::io
