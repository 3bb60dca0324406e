#pragma once
// The report's pictures and numbers of a result's maps, made a band of rows at
// a time so that a result larger than memory is reported from its files
// without being held: a first pass reads every band (the viewer's subsampled
// model, the angular error's statistics) and counts the quantiles the pictures
// are scaled by, a second gathers those quantiles exactly (io::BandQuantile),
// a third draws every picture into its overview (overview.hpp); a result small
// enough to be one band is read once for all three. Held for the
// whole image: the solved mask, the ground truth's mask and the mask of the
// compared pixels (a byte a pixel each) and the compared pixels' errors (a
// double each, in a vector that grows); the later passes draw the error from
// these, so the ground truth is decoded once.

#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/row_reader.hpp"
#include "lightstage/host/io/solve_folder_rows.hpp"
#include "lightstage/host/report/deep_zoom.hpp"
#include "lightstage/host/report/viewer_data.hpp"
#include "report/svg.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::report {

// Ground-truth normals of the result's rows, read a band at a time.
class TruthRows {
 public:
  virtual ~TruthRows() = default;
  virtual cv::Size size() const = 0;
  // Rows [y0, y0 + rows): normals and where they are given.
  virtual io::DecodedNormals read(int y0, int rows) = 0;
  // Where to compare (CV_8UC1, the result's size), or empty: where the truth is given.
  cv::Mat mask;
  std::string source;  // named in the page
};

// A Normal_gt.png (project encoding), cut to `region` of it when given (a
// `solve --crop` result's region of its stack; one reaching outside it is refused).
std::unique_ptr<TruthRows> truth_from_file(const std::filesystem::path& file,
                                           std::optional<cv::Rect> region = std::nullopt);

// How depth.pfm is drawn: its unit per pixel comes from the integration's camera.
struct DepthSource {
  std::unique_ptr<io::RowReader> rows;  // one float channel, the result's size
  double pixel_size = 1.0;              // orthographic (or unknown): depth units per pixel
  double focal_px = 0;  // > 0: perspective, a pixel spans depth / focal_px at the median depth
};

struct MapSources {
  io::SolveFolderRows* folder = nullptr;
  std::optional<DepthSource> depth;
  std::unique_ptr<io::RowReader> method_map;  // CV_8UC3 of the result's size, or none
  std::unique_ptr<TruthRows> truth;           // or none
  double albedo_scale = 0;                    // the albedo picture's white; ≤ 0: its 99.5th percentile
  int band_rows = 0;                          // 0: as many as fit kReportBandBytes
  std::size_t kept_bytes = 0;                 // maps that fit are one band, read once (ReportOptions)
  int picture_max_pixels = 1 << 21;
  int viewer_max_pixels = 1 << 20;
  // Not empty: Deep Zoom pyramids of the normal and albedo pictures at full size go there.
  std::filesystem::path pyramid_dir;
  DeepZoomOptions pyramid;
};

// A band's working set, for choosing band_rows.
inline constexpr std::size_t kReportBandBytes = std::size_t{16} << 20;

struct DepthPictures {
  cv::Mat shaded, colour;
  double low = 0, high = 0, pixel_size = 1;
};

struct ErrorPictures {
  cv::Mat map;
  double high = 0;
  HistogramCounts histogram{1, 1};
  AngularErrorStats stats;
};

struct ResultPictures {
  int factor = 1;  // each picture is the result's size / factor (overview.hpp)
  int band_rows = 0;
  cv::Mat normals, albedo;
  bool colour_albedo = false;
  double albedo_shown = 1;  // the albedo value drawn white
  std::optional<DepthPictures> depth;
  cv::Mat residual, confidence, method_map;
  double residual_high = 0;
  std::optional<ErrorPictures> error;
  SurfaceModel viewer;
  std::vector<DeepZoomSummary> pyramids;  // normals, albedo (MapSources::pyramid_dir)
};

ResultPictures draw_result_maps(MapSources& sources, std::vector<std::string>& notes);

}  // namespace lightstage::report
