#include "report/result_maps.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/io/solve_output_writer.hpp"
#include "report/maps.hpp"
#include "report/overview.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

namespace lightstage::report {

namespace fs = std::filesystem;

namespace {

// A Normal_gt.png's rows, cut to `region` of it.
class FileTruth final : public TruthRows {
 public:
  FileTruth(const fs::path& file, std::optional<cv::Rect> region) : rows_(io::open_row_reader(file)) {
    source = file.string();
    region_ = region.value_or(cv::Rect({0, 0}, rows_->size()));
    if ((region_ & cv::Rect({0, 0}, rows_->size())) != region_)
      fail("summary.json: crop [{}, {}, {}, {}] reaches outside the stack's {}x{} ground truth", region_.x,
           region_.y, region_.width, region_.height, rows_->size().width, rows_->size().height);
  }
  cv::Size size() const override { return region_.size(); }
  io::DecodedNormals read(int y0, int rows) override {
    cv::Mat encoded;
    rows_->read(region_.y + y0, rows, encoded);
    return io::decode_normal_map(encoded.colRange(region_.x, region_.x + region_.width),
                                 rows_->path().string());
  }

 private:
  std::unique_ptr<io::RowReader> rows_;
  cv::Rect region_;
};

// The finite values of `values` where `valid` is nonzero, in row order.
std::vector<float> valid_values(const cv::Mat& values, const cv::Mat& valid) {
  std::vector<float> out;
  for (int y = 0; y < values.rows; ++y)
    for (int x = 0; x < values.cols; ++x)
      if ((valid.empty() || valid.at<std::uint8_t>(y, x) != 0) && std::isfinite(values.at<float>(y, x)))
        out.push_back(values.at<float>(y, x));
  return out;
}

// A quantile of a map's valid values over every band: counted in the first pass, gathered in the second
// (maps.hpp's quantile over the whole map, exactly).
class MapQuantile {
 public:
  explicit MapQuantile(double q) : q_(q) {}
  void count(const cv::Mat& values, const cv::Mat& valid) {
    const auto v = valid_values(values, valid);
    quantile_.count(v.data(), v.size());
  }
  void locate() { found_ = quantile_.locate(q_); }
  bool located() const { return found_; }
  void gather(const cv::Mat& values, const cv::Mat& valid) {
    if (!found_) return;
    const auto v = valid_values(values, valid);
    quantile_.gather(v.data(), v.size());
  }
  double value() const { return found_ ? quantile_.value() : 0.0; }

 private:
  double q_;
  io::BandQuantile quantile_;
  bool found_ = false;
};

// Where depth can be drawn: solved, finite and not 0.
cv::Mat usable_depth(const cv::Mat& depth, const cv::Mat& solved) {
  cv::Mat usable = solved.clone();
  for (int y = 0; y < depth.rows; ++y)
    for (int x = 0; x < depth.cols; ++x)
      if (!std::isfinite(depth.at<float>(y, x)) || depth.at<float>(y, x) == 0)
        usable.at<std::uint8_t>(y, x) = 0;
  return usable;
}

}  // namespace

std::unique_ptr<TruthRows> truth_from_file(const fs::path& file, std::optional<cv::Rect> region) {
  return std::make_unique<FileTruth>(file, region);
}

ResultPictures draw_result_maps(MapSources& sources, std::vector<std::string>& notes) {
  io::SolveFolderRows& folder = *sources.folder;
  const cv::Size size = folder.size();
  const int height = size.height;
  ResultPictures out;
  const std::size_t band_bytes = folder.bytes_per_pixel() + 64;  // + depth, truth, error and the pictures
  const std::size_t row_bytes = band_bytes * static_cast<std::size_t>(size.width);
  const bool whole_kept =
      sources.band_rows <= 0 && row_bytes * static_cast<std::size_t>(height) <= sources.kept_bytes;
  out.band_rows = sources.band_rows > 0 ? sources.band_rows
                  : whole_kept          ? height
                               : static_cast<int>(std::clamp<std::size_t>(kReportBandBytes / row_bytes, 1,
                                                                          static_cast<std::size_t>(height)));
  const int step = out.band_rows;
  // A result read as one band is decoded once: its maps, depth and errors serve every pass.
  const bool one_band = step >= height;
  std::optional<io::SolveFolder> kept_maps;
  cv::Mat kept_depth;
  std::optional<AngularErrorMap> kept_error;
  cv::Mat solved(size, CV_8UC1);  // filled by the first pass
  // The first pass reads every map; the later ones only the maps they use, and
  // the solved mask from the first (normal.png then needs no decoding beside normal.exr).
  const auto read_maps = [&](int y0, int rows, const io::SolveFolderRows::Wanted* later) {
    if (one_band) {
      if (!kept_maps) kept_maps = folder.read(y0, rows);
      return *kept_maps;
    }
    return later ? folder.read(y0, rows, *later, solved.rowRange(y0, y0 + rows)) : folder.read(y0, rows);
  };
  // Every band top to bottom: its maps (as read_maps with `later`) and, with
  // `truth`, its ground truth are read beside the visit of the band before
  // (two bands held at once, report_memory_bytes).
  struct BandRead {
    io::SolveFolder maps;
    io::DecodedNormals truth;
  };
  const auto for_each_band = [&](const io::SolveFolderRows::Wanted* later, bool truth, auto&& visit) {
    const auto read = [&](int y0, int rows) {
      BandRead band{read_maps(y0, rows, later), {}};
      if (truth) band.truth = sources.truth->read(y0, rows);
      return band;
    };
    std::optional<BandRead> current;
    for (int y = 0; y < height; y += step) {
      const int rows = std::min(step, height - y), next_y = y + step;
      if (!current) current = read(y, rows);
      std::optional<BandRead> next;
      std::vector<std::function<void()>> tasks{[&] { visit(y, rows, *current); }};
      if (next_y < height) tasks.emplace_back([&] { next = read(next_y, std::min(step, height - next_y)); });
      parallel_invoke(tasks, 0);
      current = std::move(next);
    }
  };
  const auto read_depth = [&](int y0, int rows) {
    if (one_band && !kept_depth.empty()) return kept_depth;
    cv::Mat depth;
    sources.depth->rows->read(y0, rows, depth);
    if (one_band) kept_depth = depth;
    return depth;
  };

  // Pass 1: the viewer's model, the error's statistics, the quantiles counted.
  SurfaceModelBuilder viewer(folder, sources.viewer_max_pixels, notes);
  MapQuantile albedo_q(0.995), residual_q(0.99), depth_median(0.5), error_q(0.95);
  float depth_low = std::numeric_limits<float>::infinity(), depth_high = -depth_low;
  AngularErrorAccumulator errors;
  const bool scale_albedo = !(sources.albedo_scale > 0) && folder.has_albedo();
  // The band's error map, and the truth's mask of it: computed in the first
  // pass, where the errors gathered keep their pixel order and the whole
  // image's mask of them is kept; the later passes replay them from there
  // (the truth is decoded and the angles computed once).
  cv::Mat error_valid;
  std::size_t replayed = 0;  // errors replayed so far in this pass
  const auto error_rows = [&](const io::SolveFolder& band, const io::DecodedNormals& truth, int y0,
                              int rows) {
    if (one_band && kept_error) return *kept_error;
    AngularErrorMap map;
    map.degrees = cv::Mat(rows, size.width, CV_32FC1, cv::Scalar::all(0));
    map.valid = cv::Mat(rows, size.width, CV_8UC1, cv::Scalar::all(0));
    const cv::Mat mask =
        sources.truth->mask.empty() ? truth.valid : sources.truth->mask.rowRange(y0, y0 + rows);
    errors.add(band.normals, truth.normals, mask, &map);
    if (one_band) {
      kept_error = map;
      return map;
    }
    if (error_valid.empty()) error_valid = cv::Mat(size, CV_8UC1, cv::Scalar::all(0));
    map.valid.copyTo(error_valid.rowRange(y0, y0 + rows));
    return map;
  };
  const auto replay_error_rows = [&](int y0, int rows) {
    if (one_band && kept_error) return *kept_error;
    AngularErrorMap map;
    map.degrees = cv::Mat(rows, size.width, CV_32FC1, cv::Scalar::all(0));
    map.valid = error_valid.rowRange(y0, y0 + rows);
    const std::vector<double>& gathered = errors.errors();
    for (int y = 0; y < rows; ++y) {
      const auto* valid = map.valid.ptr<std::uint8_t>(y);
      auto* degrees = map.degrees.ptr<float>(y);
      for (int x = 0; x < size.width; ++x)
        if (valid[x] != 0) degrees[x] = static_cast<float>(gathered.at(replayed++));
    }
    return map;
  };
  for_each_band(nullptr, sources.truth != nullptr, [&](int y0, int rows, const BandRead& read) {
    const io::SolveFolder& band = read.maps;
    viewer.add(band, y0);
    band.solved.copyTo(solved.rowRange(y0, y0 + rows));
    if (scale_albedo) albedo_q.count(band.albedo, band.solved);
    if (!band.residual.empty()) residual_q.count(band.residual, band.solved);
    if (sources.depth) {
      const cv::Mat depth = read_depth(y0, rows);
      const cv::Mat usable = usable_depth(depth, band.solved);
      for (const float v : valid_values(depth, usable)) {
        depth_low = std::min(depth_low, v);
        depth_high = std::max(depth_high, v);
      }
      if (sources.depth->focal_px > 0) depth_median.count(depth, usable);
    }
    if (sources.truth) {
      const AngularErrorMap map = error_rows(band, read.truth, y0, rows);
      error_q.count(map.degrees, map.valid);
    }
  });
  out.viewer = viewer.finish();
  for (MapQuantile* q : {&albedo_q, &residual_q, &depth_median, &error_q}) q->locate();

  // Pass 2: the quantiles gathered, from only the maps they need (none to gather: no second read).
  io::SolveFolderRows::Wanted gathered;
  gathered.albedo = albedo_q.located();
  gathered.residual = residual_q.located();
  gathered.normals = false;  // the error map's are replayed
  gathered.colour = gathered.confidence = gathered.coefficients = false;
  const bool gather_depth = depth_median.located();
  replayed = 0;
  if (gathered.albedo || gathered.residual || error_q.located() || gather_depth)
    for_each_band(&gathered, false, [&](int y0, int rows, const BandRead& read) {
      const io::SolveFolder& band = read.maps;
      if (gathered.albedo) albedo_q.gather(band.albedo, band.solved);
      if (gathered.residual) residual_q.gather(band.residual, band.solved);
      if (gather_depth) {
        const cv::Mat depth = read_depth(y0, rows);
        depth_median.gather(depth, usable_depth(depth, band.solved));
      }
      if (error_q.located()) {
        const AngularErrorMap map = replay_error_rows(y0, rows);
        error_q.gather(map.degrees, map.valid);
      }
    });

  // Pass 3: every picture drawn.
  replayed = 0;
  out.factor = overview_factor(size, sources.picture_max_pixels);
  const auto overview = [&] { return Overview(size, out.factor); };
  Overview normals = overview(), albedo = overview(), shaded = overview(), depth_colour = overview(),
           residual = overview(), confidence = overview(), error_map = overview();
  Overview method_map(size, out.factor, Overview::Blocks::kFirstPixel);
  out.colour_albedo = folder.has_albedo() && folder.has_chroma();
  out.albedo_shown = sources.albedo_scale > 0 ? sources.albedo_scale : std::max(albedo_q.value(), 1e-12);
  out.residual_high = nice_ceiling(residual_q.value());
  DepthPictures depth_pictures;
  if (sources.depth) {
    depth_pictures.low = std::isfinite(depth_low) ? depth_low : 0.0;
    depth_pictures.high = std::isfinite(depth_high) ? depth_high : 0.0;
    depth_pictures.pixel_size = sources.depth->pixel_size;
    if (sources.depth->focal_px > 0 && depth_median.value() > 0)
      depth_pictures.pixel_size = depth_median.value() / sources.depth->focal_px;
  }
  ErrorPictures error;
  if (sources.truth) {
    error.high = nice_ceiling(std::max(error_q.value(), 0.1));
    error.histogram = HistogramCounts(error.high, 40);
  }
  bool method_map_ok = sources.method_map != nullptr;
  std::unique_ptr<DeepZoomWriter> normal_pyramid, albedo_pyramid;
  if (!sources.pyramid_dir.empty()) {
    normal_pyramid =
        std::make_unique<DeepZoomWriter>(sources.pyramid_dir / "normal.dzi", size, sources.pyramid);
    albedo_pyramid =
        std::make_unique<DeepZoomWriter>(sources.pyramid_dir / "albedo.dzi", size, sources.pyramid);
  }
  io::SolveFolderRows::Wanted drawn;
  drawn.coefficients = false;
  for_each_band(&drawn, false, [&](int y0, int rows, const BandRead& read) {
    const io::SolveFolder& band = read.maps;
    const cv::Mat normal_picture = normal_colours(band.normals, band.solved);
    normals.add(normal_picture);
    const cv::Mat grey_albedo =
        band.albedo.empty() ? cv::Mat(band.solved.size(), CV_32FC1, cv::Scalar(0)) : band.albedo;
    const cv::Mat albedo_picture =
        grey(out.colour_albedo ? band.colour_albedo() : grey_albedo, band.solved, out.albedo_shown);
    albedo.add(albedo_picture);
    if (normal_pyramid) {
      normal_pyramid->add(normal_picture);
      albedo_pyramid->add(albedo_picture);
    }
    if (sources.depth) {
      // One row more on either side: the relief's slopes at the band's edges.
      const int top = std::max(0, y0 - 1), bottom = std::min(height, y0 + rows + 1);
      const cv::Mat depth = read_depth(top, bottom - top);
      const cv::Mat usable = usable_depth(depth, solved.rowRange(top, bottom));
      const cv::Range inner(y0 - top, y0 - top + rows);
      shaded.add(shaded_depth(depth, usable, depth_pictures.pixel_size).rowRange(inner));
      depth_colour.add(false_colour(depth.rowRange(inner), usable.rowRange(inner), depth_pictures.low,
                                    depth_pictures.high, kDepthColormap));
    }
    if (!band.residual.empty())
      residual.add(false_colour(band.residual, band.solved, 0, out.residual_high, kMagnitudeColormap));
    if (!band.confidence.empty())
      confidence.add(false_colour(band.confidence, band.solved, 0, 1.0, kMagnitudeColormap));
    if (method_map_ok) {
      try {
        cv::Mat choices;
        sources.method_map->read(y0, rows, choices);
        method_map.add(choices);
      } catch (const InputError& e) {
        notes.push_back(fmt::format("method_map.png: {}; not shown.", e.what()));
        method_map_ok = false;
      }
    }
    if (sources.truth) {
      const AngularErrorMap map = replay_error_rows(y0, rows);
      error_map.add(false_colour(map.degrees, map.valid, 0, error.high, kMagnitudeColormap));
      for (int y = 0; y < map.degrees.rows; ++y)
        for (int x = 0; x < map.degrees.cols; ++x)
          if (map.valid.at<std::uint8_t>(y, x) != 0) error.histogram.add(map.degrees.at<float>(y, x));
    }
  });
  out.normals = normals.finish();
  out.albedo = albedo.finish();
  if (normal_pyramid) out.pyramids = {normal_pyramid->finish(), albedo_pyramid->finish()};
  if (sources.depth) {
    depth_pictures.shaded = shaded.finish();
    depth_pictures.colour = depth_colour.finish();
    out.depth = std::move(depth_pictures);
  }
  if (folder.has_residual()) out.residual = residual.finish();
  if (folder.has_confidence()) out.confidence = confidence.finish();
  if (method_map_ok) out.method_map = method_map.finish();
  if (sources.truth) {
    error.stats = errors.stats();  // sorts the errors: after the last replay
    error.map = error_map.finish();
    out.error = std::move(error);
  }
  return out;
}

}  // namespace lightstage::report
