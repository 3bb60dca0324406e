#pragma once
// A solve folder (solve_output.hpp) read a band of rows at a time: every map's
// rows decoded as read_solve_folder decodes them, from row readers kept open
// (row_reader.hpp), so that a result larger than memory is read through
// without being held. read_solve_folder is this reader's one band of every row.

#include "lightstage/host/io/solve_output.hpp"

#include <filesystem>
#include <memory>
#include <vector>

namespace lightstage::io {

class RowReader;

class SolveFolderRows {
 public:
  // Opens normal.png and every other map the folder holds (as read_solve_folder
  // reads them) and checks their sizes against it. Throws InputError naming the
  // file that does not open or match.
  explicit SolveFolderRows(const std::filesystem::path& dir);
  ~SolveFolderRows();
  SolveFolderRows(const SolveFolderRows&) = delete;
  SolveFolderRows& operator=(const SolveFolderRows&) = delete;

  // The folder's facts (dir, summary, scales, reflectance) with no maps.
  const SolveFolder& facts() const { return facts_; }
  cv::Size size() const { return size_; }
  bool has_albedo() const { return albedo_pfm_ || albedo_png_; }
  bool has_chroma() const { return colour_ != nullptr; }
  bool has_residual() const { return residual_ != nullptr; }
  bool has_confidence() const { return confidence_ != nullptr; }
  // Bytes a pixel of the maps read() returns.
  std::size_t bytes_per_pixel() const;

  // The maps a read decodes (those the folder holds); the others stay empty.
  struct Wanted {
    bool normals = true;
    bool albedo = true;
    bool colour = true;  // the colour albedo's chroma; decodes the grey albedo too
    bool residual = true;
    bool confidence = true;
    bool coefficients = true;
  };

  // Rows [y0, y0 + rows): a SolveFolder of those rows with facts()'s facts.
  // Bands read top to bottom decode each file they read once. Throws
  // InputError naming a file that fails to decode at those rows.
  //
  // `solved`, when not empty, is those rows' solved mask from an earlier read:
  // normal.png is then decoded only when there is no normal.exr to take the
  // normals from (its own mask is then returned), or not at all when the
  // normals are not wanted. The band's `solved` shares the caller's pixels.
  SolveFolder read(int y0, int rows, const Wanted& wanted, const cv::Mat& solved = cv::Mat());
  SolveFolder read(int y0, int rows) { return read(y0, rows, Wanted{}); }

 private:
  // The wanted maps but the normals, rows [y0, y0 + rows), into `band`.
  void read_maps(int y0, int rows, const Wanted& wanted, SolveFolder& band);

  SolveFolder facts_;
  cv::Size size_;
  std::unique_ptr<RowReader> normal_png_, normal_exr_, albedo_pfm_, albedo_png_, colour_, residual_,
      confidence_;
  std::vector<std::unique_ptr<RowReader>> coefficients_;
};

}  // namespace lightstage::io
