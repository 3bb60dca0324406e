#include "lightstage/host/io/row_writer.hpp"

#include "lightstage/common/error.hpp"

#include <fmt/format.h>

#include <utility>

namespace lightstage::io {

RowWriter::RowWriter(std::filesystem::path path, cv::Size size, int type)
    : path_(std::move(path)), size_(size), type_(type) {
  if (size.width <= 0 || size.height <= 0)
    fail("{}: cannot write an image of {}x{}", path_.string(), size.width, size.height);
}

void RowWriter::write(const cv::Mat& rows) {
  if (rows.empty()) return;
  if (rows.type() != type_ || rows.cols != size_.width)
    fail("{}: rows of {} and width {} given, the image is {} of width {}", path_.string(),
         cv::typeToString(rows.type()), rows.cols, cv::typeToString(type_), size_.width);
  if (rows.rows > size_.height - next_row_)
    fail("{}: {} more rows given after {} of {}", path_.string(), rows.rows, next_row_, size_.height);
  write_rows(rows, next_row_);
  next_row_ += rows.rows;
}

void RowWriter::commit() {
  if (next_row_ != size_.height)
    fail("{}: {} of {} rows written: the image is not complete", path_.string(), next_row_, size_.height);
  finish();
}

}  // namespace lightstage::io
