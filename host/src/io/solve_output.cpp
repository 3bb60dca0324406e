#include "lightstage/host/io/solve_output.hpp"

#include "lightstage/host/io/solve_folder_rows.hpp"

#include <vector>

namespace lightstage::io {

cv::Mat times_chroma(const cv::Mat& albedo, const cv::Mat& chroma) {
  cv::Mat albedo3;
  cv::merge(std::vector<cv::Mat>{albedo, albedo, albedo}, albedo3);
  return albedo3.mul(chroma);
}

cv::Mat SolveFolder::colour_albedo() const {
  return albedo.empty() || chroma.empty() ? albedo : times_chroma(albedo, chroma);
}

cv::Mat SolveFolder::display_albedo() const {
  if (albedo.empty()) return {};
  cv::Mat shown = colour_albedo() / (chroma.empty() ? albedo_png_scale : albedo_rgb_png_scale);
  cv::min(shown, 1.0, shown);
  cv::max(shown, 0.0, shown);
  return shown;
}

SolveFolder read_solve_folder(const std::filesystem::path& dir) {
  SolveFolderRows rows(dir);
  return rows.read(0, rows.size().height);
}

}  // namespace lightstage::io
