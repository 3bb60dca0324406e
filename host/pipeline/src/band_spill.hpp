#pragma once
// A solve's bands kept on disk between the passes that need them again: the
// bi-polynomial's relighting refit (solve_bands.cpp) reads every band's
// normals twice more, once for the object-wide sample and once to refit each
// pixel, and only then are the maps written. Each band's maps go to one
// hidden file in the output folder as they come and are read back in the same
// order; the file goes with the spill.

#include "lightstage/host/solvers/solve_result.hpp"

#include <filesystem>
#include <fstream>

namespace lightstage::pipeline::bands {

class BandSpill {
 public:
  // A file in `dir` (which must exist), removed when the spill is destroyed.
  explicit BandSpill(const std::filesystem::path& dir);
  ~BandSpill();
  BandSpill(const BandSpill&) = delete;
  BandSpill& operator=(const BandSpill&) = delete;

  // The next band's maps (normals, albedo, residual, solved, confidence,
  // chroma, coefficients, choice); empty normals stand for `rows` rows
  // without a pixel to solve. Throws Error naming the file when it cannot be
  // written (a full disk).
  void write(const SolveResult& band, int rows);
  // Back to the first band: read() gives the bands in the order written.
  void rewind();
  // The next band's maps and its row count. Throws Error past the last band.
  SolveResult read(int& rows);

 private:
  std::filesystem::path path_;
  std::fstream file_;
  bool writing_ = true;
};

}  // namespace lightstage::pipeline::bands
