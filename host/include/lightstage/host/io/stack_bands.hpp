#pragma once
// A stack folder read a band of rows at a time, for stacks larger than memory.
// Opening reads the index (names, lights, manifest), the mask, every image's
// header (the checks load_stack makes before decoding: sizes, the caps of
// stack_io.hpp) and opens the first frame, dark frames and ground truth for
// reading by rows (io/row_reader.hpp); it is cheap enough to size a solve
// before deciding how to read the stack. The first read_band() opens the
// other frames (refusing one of another size or type); each call decodes the
// same rows of every image (each file beside the others, its decoding carried
// on from the band before; with several bad files the error is load_stack's)
// into an ImageStack that is exactly those rows of what load_stack gives: the
// same frames, fields and values, dark frames, mask and ground truth. Float
// pixels are checked finite band by band. Camera RAW files and interlaced
// PNGs decode only whole: each such frame is decoded at the first band and
// its rows kept in a temporary file (row_reader.hpp).

#include "lightstage/common/image_stack.hpp"
#include "lightstage/host/io/stack_io.hpp"

#include <opencv2/core.hpp>

#include <cstddef>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace lightstage::io {

class RowReader;

class StackBands {
 public:
  // Throws InputError, naming the file and field, for what load_stack refuses
  // before decoding.
  explicit StackBands(const std::filesystem::path& dir, const LoadOptions& options = {});
  ~StackBands();
  StackBands(const StackBands&) = delete;
  StackBands& operator=(const StackBands&) = delete;

  const std::filesystem::path& folder() const { return dir_; }
  // The stack without pixels: frames as load_stack gives them with empty
  // images and darks, the whole mask, no ground truth.
  const ImageStack& index() const { return index_; }
  cv::Size size() const { return size_; }
  int type() const { return type_; }  // the frames' OpenCV type

  // Rows [y0, y0 + rows) of the stack. Throws InputError naming the file for
  // a frame of another size or type than the first (first call), rows
  // outside the images, a file that fails to decode there, or a float pixel
  // that is not finite (named by its place in the whole image).
  ImageStack read_band(int y0, int rows);
  // The rows read_band has decoded so far, summed over its calls: how many
  // passes over the stack a solve took.
  std::size_t rows_read() const { return rows_read_; }

 private:
  void open_frames();

  std::filesystem::path dir_;
  LoadOptions options_;
  ImageStack index_;
  cv::Size size_;
  int type_ = 0;
  std::vector<std::unique_ptr<RowReader>> frames_;
  std::map<std::string, std::unique_ptr<RowReader>> darks_;  // by file name, shared by the frames naming it
  std::unique_ptr<RowReader> normals_, depth_;
  bool opened_ = false;
  std::size_t rows_read_ = 0;
};

}  // namespace lightstage::io
