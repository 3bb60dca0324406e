#pragma once
// A solve folder (solve_output.hpp) written band by band, top to bottom, as a
// solve makes its rows: every map goes to its file as the rows come, so a
// result larger than memory is never held whole. What needs the whole image
// (the PNG scales: a percentile over every solved pixel) is found exactly from
// a histogram of the rows and a second read of the float maps already
// written. write_solve_outputs is this writer given the whole result at once.

#include "lightstage/host/io/row_writer.hpp"
#include "lightstage/host/solvers/solve_result.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace lightstage::io {

// The value nth_element would put at floor(q · (n − 1)) among the finite
// values of every band, exact and in constant memory: a histogram of the top
// 16 bits of their order-keeping keys, then, in a second pass over the same
// values, of the low 16 bits within the one bucket that holds it.
class BandQuantile {
 public:
  void count(const float* values, std::size_t n);
  // After every count: false when there were no finite values.
  bool locate(double q);
  void gather(const float* values, std::size_t n);
  float value() const;  // after gathering every band again

 private:
  std::vector<std::uint64_t> histogram_ = std::vector<std::uint64_t>(1 << 16, 0);
  std::uint64_t total_ = 0;
  std::uint32_t bucket_ = 0;
  std::uint64_t rank_ = 0;  // within the bucket
};

class SolveOutputWriter {
 public:
  // Creates `dir`; the files appear when finish() has written them all.
  // Destroyed unfinished, it leaves nothing (nor the folder, when it made it).
  SolveOutputWriter(std::filesystem::path dir, cv::Size size);
  ~SolveOutputWriter();
  SolveOutputWriter(const SolveOutputWriter&) = delete;
  SolveOutputWriter& operator=(const SolveOutputWriter&) = delete;

  // The next band.normals.rows rows. Maps a method does not make stay empty
  // (every band of a solve makes the same ones).
  void add(const SolveResult& band);
  // The next `rows` rows had no pixel to solve: zeros in every map.
  void add_empty(int rows);
  // After the last row: the PNGs scaled by the whole result, summary.json of
  // `result`'s summary, parameters, reflectance and choices (its maps are not
  // read), `input` and `extra`'s keys. Returns summary.json.
  nlohmann::json finish(const SolveResult& result, const std::filesystem::path& input,
                        const nlohmann::json& extra);

 private:
  void open(const SolveResult& band);
  void write_rows(const SolveResult& band);

  std::filesystem::path dir_;
  cv::Size size_;
  int rows_ = 0;
  int pending_empty_ = 0;  // rows before the first band with a pixel
  bool opened_ = false;
  bool created_ = false;  // the folder did not exist before
  bool finished_ = false;
  bool colour_ = false;
  cv::Mat solved_;  // the whole image's: the PNG scales count solved pixels only
  BandQuantile albedo_white_, colour_white_;
  std::unique_ptr<RowWriter> normal_png_, normal_vis_, albedo_pfm_, residual_pfm_, normal_exr_, albedo_exr_,
      colour_pfm_, colour_exr_, confidence_pfm_, method_map_;
  std::vector<std::unique_ptr<RowWriter>> coefficient_pfms_;
  std::vector<std::string> coefficient_files_;
  std::vector<std::filesystem::path> committed_;  // removed again if finish() fails after them
  std::vector<std::string> choices_;
  std::vector<std::size_t> choice_counts_;
};

}  // namespace lightstage::io
