#include "lightstage/host/io/raw_image.hpp"

#include "io/ascii_text.hpp"
#include "io/file_extension.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/stack_io.hpp"

#include <fmt/format.h>
#include <libraw/libraw.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <new>
#include <string_view>
#include <system_error>

namespace lightstage::io {
namespace {

constexpr std::string_view kRawExtensions[] = {
    ".dng", ".cr2", ".cr3", ".crw", ".nef", ".nrw", ".arw", ".srf", ".sr2", ".orf", ".rw2", ".raf", ".pef",
    ".srw", ".3fr", ".fff", ".iiq", ".erf", ".kdc", ".dcr", ".mos", ".mef", ".mrw", ".x3f", ".rwl", ".raw"};
constexpr double kFullScale = 65535.0;
constexpr unsigned kXTrans = 9;  // LibRaw's `filters` for a 6×6 X-Trans mosaic
constexpr unsigned kPatternedFilters = 1000;
// Twice a stack's largest side (binning halves it); no camera's sensor is larger.
constexpr int kMaxSensorSide = 2 * static_cast<int>(kMaxImageSide);

struct LibRawDeleter {
  void operator()(LibRaw* raw) const { delete raw; }
};
using RawHandle = std::unique_ptr<LibRaw, LibRawDeleter>;

// LibRaw reports data corruption through a callback and reads on; we stop.
void note_data_error(void* data, const char*, const int offset) {
  auto* first = static_cast<int*>(data);
  if (*first < 0) *first = std::max(offset, 0);
}

RawHandle open_raw(const std::filesystem::path& path, int* data_error) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) fail("{}: no such file", path.string());
  if (!std::filesystem::is_regular_file(path, error)) fail("{}: not a regular file", path.string());
  RawHandle raw(new LibRaw(LIBRAW_OPTIONS_NONE));
  raw->set_dataerror_handler(note_data_error, data_error);
  const int rc = raw->open_file(path.c_str());
  if (rc != LIBRAW_SUCCESS)
    fail("{}: not a RAW file LibRaw can read ({})", path.string(), libraw_strerror(rc));
  const auto& sizes = raw->imgdata.sizes;
  if (sizes.width < 2 || sizes.height < 2 || sizes.width > kMaxSensorSide || sizes.height > kMaxSensorSide ||
      sizes.raw_width > kMaxSensorSide || sizes.raw_height > kMaxSensorSide)
    fail("{}: RAW image of {}x{} pixels (each side 2 to {})", path.string(), sizes.width, sizes.height,
         kMaxSensorSide);
  return raw;
}

// The 2×2 colour letters of a Bayer mosaic ("RGGB", ...), or empty when the
// mosaic does not repeat every 2×2 pixels or is not red, two greens and blue.
std::string bayer_pattern(LibRaw& raw) {
  const unsigned filters = raw.imgdata.idata.filters;
  if (filters < kPatternedFilters) return {};
  for (int row = 0; row < 16; ++row)
    for (int col = 0; col < 2; ++col)
      if (raw.COLOR(row, col) != raw.COLOR(row % 2, col)) return {};
  std::string letters;
  for (int site = 0; site < 4; ++site) {
    const int colour = raw.COLOR(site / 2, site % 2);
    letters += colour >= 0 && colour < 4 ? raw.imgdata.idata.cdesc[colour] : '?';
  }
  std::string sorted = letters;
  std::sort(sorted.begin(), sorted.end());
  return sorted == "BGGR" ? letters : std::string();
}

// The black level of one pixel (visible coordinates) of colour `colour`:
// LibRaw's common level, the colour's level and the pattern level.
struct BlackLevels {
  const libraw_colordata_t* colour_data = nullptr;
  unsigned pattern_rows = 0, pattern_cols = 0;

  double at(int row, int col, int colour) const {
    const auto& c = *colour_data;
    double black = static_cast<double>(c.black) + c.cblack[std::clamp(colour, 0, 3)];
    if (pattern_rows > 0 && pattern_cols > 0)
      black += c.cblack[6 + (static_cast<unsigned>(row) % pattern_rows) * pattern_cols +
                        static_cast<unsigned>(col) % pattern_cols];
    return black;
  }
};

BlackLevels black_levels(const std::filesystem::path& path, const libraw_colordata_t& colour) {
  BlackLevels levels;
  levels.colour_data = &colour;
  levels.pattern_rows = colour.cblack[4];
  levels.pattern_cols = colour.cblack[5];
  if (levels.pattern_rows > 64 || levels.pattern_cols > 64 ||
      levels.pattern_rows * levels.pattern_cols > 4096)
    fail("{}: black level pattern of {}x{} sites", path.string(), levels.pattern_rows, levels.pattern_cols);
  return levels;
}

// The highest black level any pixel can have: common + colour + pattern parts.
double highest_black(const libraw_colordata_t& colour, const BlackLevels& levels) {
  double highest = *std::max_element(colour.cblack, colour.cblack + 4);
  double pattern = 0;
  for (unsigned i = 0; i < levels.pattern_rows * levels.pattern_cols; ++i)
    pattern = std::max(pattern, static_cast<double>(colour.cblack[6 + i]));
  return static_cast<double>(colour.black) + highest + pattern;
}

// Whether `demosaic` bins this file 2×2 as it lies in raw_image: half size
// asked for, a Bayer pattern on square pixels, not rotated 45° (Fujifilm SuperCCD).
bool bins(LibRaw& raw, RawDemosaic demosaic) {
  return demosaic == RawDemosaic::half && !bayer_pattern(raw).empty() && !raw.is_fuji_rotated() &&
         raw.imgdata.sizes.pixel_aspect == 1.0;
}

cv::Size output_size(const LibRaw& raw, bool binned) {
  const auto& sizes = raw.imgdata.sizes;
  return binned ? cv::Size(sizes.width / 2, sizes.height / 2) : cv::Size(sizes.width, sizes.height);
}

// The visible area and row pitch LibRaw reports must lie inside the buffer it decoded into.
void check_geometry(const std::filesystem::path& path, const LibRaw& raw, int values_per_pixel) {
  const auto& s = raw.imgdata.sizes;
  if (s.left_margin + s.width > s.raw_width || s.top_margin + s.height > s.raw_height ||
      static_cast<std::size_t>(s.raw_pitch) <
          static_cast<std::size_t>(s.raw_width) * values_per_pixel * sizeof(std::uint16_t))
    fail("{}: inconsistent RAW geometry (visible {}x{} at {},{} of {}x{}, pitch {} bytes)", path.string(),
         s.width, s.height, s.left_margin, s.top_margin, s.raw_width, s.raw_height, s.raw_pitch);
}

// One site's value on the output scale: 65535 at or above white, else at most 65534.
double normalised(unsigned value, double black, double white) {
  if (value >= white) return kFullScale;
  return std::clamp((value - black) / (white - black) * kFullScale, 0.0, kFullScale - 1);
}

std::uint16_t rounded(double value) {
  return static_cast<std::uint16_t>(value >= kFullScale ? kFullScale
                                                        : std::min(std::round(value), kFullScale - 1));
}

class RawPixels {
 public:
  explicit RawPixels(const LibRaw& raw)
      : data_(raw.imgdata.rawdata.raw_image),
        pitch_(raw.imgdata.sizes.raw_pitch / sizeof(std::uint16_t)),
        top_(raw.imgdata.sizes.top_margin),
        left_(raw.imgdata.sizes.left_margin) {}
  unsigned at(int row, int col) const { return data_[(row + top_) * pitch_ + col + left_]; }

 private:
  const std::uint16_t* data_;
  std::size_t pitch_;
  std::size_t top_, left_;
};

// Half size: each 2×2 block's red, mean green and blue; BGR in memory.
cv::Mat bin_bayer(LibRaw& raw, const BlackLevels& black, double white) {
  const int width = raw.imgdata.sizes.width / 2, height = raw.imgdata.sizes.height / 2;
  const RawPixels pixels(raw);
  int channel_of_site[4];  // BGR channel of each site of the 2×2 block
  for (int site = 0; site < 4; ++site) {
    const char letter = raw.imgdata.idata.cdesc[raw.COLOR(site / 2, site % 2)];
    channel_of_site[site] = letter == 'R' ? 2 : letter == 'G' ? 1 : 0;
  }
  cv::Mat out(height, width, CV_16UC3);
  for (int y = 0; y < height; ++y) {
    auto* row = out.ptr<std::uint16_t>(y);
    for (int x = 0; x < width; ++x) {
      double sum[3] = {0, 0, 0};
      bool clipped[3] = {false, false, false};
      for (int site = 0; site < 4; ++site) {
        const int r = 2 * y + site / 2, c = 2 * x + site % 2;
        const double v = normalised(pixels.at(r, c), black.at(r, c, raw.COLOR(r, c)), white);
        const int channel = channel_of_site[site];
        sum[channel] += v;
        clipped[channel] = clipped[channel] || v >= kFullScale;
      }
      for (int channel = 0; channel < 3; ++channel) {
        const double mean = channel == 1 ? sum[1] / 2 : sum[channel];
        row[3 * x + channel] = clipped[channel] ? static_cast<std::uint16_t>(kFullScale) : rounded(mean);
      }
    }
  }
  return out;
}

cv::Mat monochrome(LibRaw& raw, const BlackLevels& black, double white) {
  const RawPixels pixels(raw);
  cv::Mat out(raw.imgdata.sizes.height, raw.imgdata.sizes.width, CV_16UC1);
  for (int y = 0; y < out.rows; ++y) {
    auto* row = out.ptr<std::uint16_t>(y);
    for (int x = 0; x < out.cols; ++x)
      row[x] = rounded(normalised(pixels.at(y, x), black.at(y, x, 0), white));
  }
  return out;
}

// A linear DNG (or sRAW): three or four values per pixel, already demosaiced.
cv::Mat linear(LibRaw& raw, const BlackLevels& black, double white) {
  const auto& sizes = raw.imgdata.sizes;
  const auto& rawdata = raw.imgdata.rawdata;
  const int values = rawdata.color4_image != nullptr ? 4 : 3;
  const auto* base =
      rawdata.color4_image != nullptr ? &rawdata.color4_image[0][0] : &rawdata.color3_image[0][0];
  const std::size_t pitch = sizes.raw_pitch / sizeof(std::uint16_t);
  cv::Mat out(sizes.height, sizes.width, CV_16UC3);
  for (int y = 0; y < out.rows; ++y) {
    const std::uint16_t* in = base + (y + sizes.top_margin) * pitch + sizes.left_margin * values;
    auto* row = out.ptr<std::uint16_t>(y);
    for (int x = 0; x < out.cols; ++x)
      for (int c = 0; c < 3; ++c)  // R, G, B in the file; B, G, R in memory
        row[3 * x + 2 - c] = rounded(normalised(in[x * values + c], black.at(y, x, c), white));
  }
  return out;
}

// Interpolation spreads a clipped site into its neighbours without clipping
// them: every output pixel within 2 sites of one reads 65535 (saturated).
void mark_clipped_neighbourhoods(LibRaw& raw, double white, cv::Mat& image) {
  const auto& sizes = raw.imgdata.sizes;
  if (raw.imgdata.rawdata.raw_image == nullptr || image.size() != cv::Size(sizes.width, sizes.height)) return;
  const RawPixels pixels(raw);
  cv::Mat clipped(image.size(), CV_8UC1, cv::Scalar::all(0));
  for (int y = 0; y < clipped.rows; ++y)
    for (int x = 0; x < clipped.cols; ++x)
      if (pixels.at(y, x) >= white) clipped.at<std::uint8_t>(y, x) = 255;
  cv::dilate(clipped, clipped, cv::Mat::ones(5, 5, CV_8UC1));
  image.setTo(cv::Scalar::all(kFullScale), clipped);
}

// LibRaw's own demosaic with nothing but black subtraction and scaling to white.
cv::Mat demosaic_full(const std::filesystem::path& path, LibRaw& raw) {
  auto& params = raw.imgdata.params;
  params.output_bps = 16;
  params.gamm[0] = 1;
  params.gamm[1] = 1;
  params.no_auto_bright = 1;
  params.use_camera_wb = 0;
  params.use_auto_wb = 0;
  std::fill(std::begin(params.user_mul), std::end(params.user_mul), 1.0f);
  params.output_color = 0;  // the camera's raw colour space: no matrix
  params.use_camera_matrix = 0;
  params.highlight = 0;           // clip at white
  params.adjust_maximum_thr = 0;  // the file's white level, not the brightest value seen
  params.user_flip = 0;           // sensor orientation, as the half-size path keeps it
  params.half_size = 0;
  int rc = raw.dcraw_process();
  if (rc != LIBRAW_SUCCESS) fail("{}: cannot demosaic ({})", path.string(), libraw_strerror(rc));
  std::unique_ptr<libraw_processed_image_t, void (*)(libraw_processed_image_t*)> image(
      raw.dcraw_make_mem_image(&rc), LibRaw::dcraw_clear_mem);
  if (!image || rc != LIBRAW_SUCCESS) fail("{}: cannot demosaic ({})", path.string(), libraw_strerror(rc));
  if (image->type != LIBRAW_IMAGE_BITMAP || image->bits != 16 || (image->colors != 3 && image->colors != 1))
    fail("{}: LibRaw gave a {}-bit image of {} colours", path.string(), image->bits, image->colors);
  const cv::Mat rgb(image->height, image->width, CV_16UC(image->colors), image->data);
  cv::Mat out;
  if (image->colors == 1) {
    out = rgb.clone();
  } else {
    out.create(rgb.size(), CV_16UC3);
    const int from_to[] = {0, 2, 1, 1, 2, 0};
    cv::mixChannels(&rgb, 1, &out, 1, from_to, 3);
  }
  return out;
}

}  // namespace

std::string to_string(RawDemosaic demosaic) { return demosaic == RawDemosaic::half ? "half" : "full"; }

RawDemosaic parse_raw_demosaic(const std::string& word, const std::string& what) {
  if (word == "half") return RawDemosaic::half;
  if (word == "full") return RawDemosaic::full;
  fail("{}: '{}' is not a demosaic (half or full)", what, word);
}

bool is_raw_file(const std::filesystem::path& path) {
  const std::string extension = lower_extension(path);
  return std::find(std::begin(kRawExtensions), std::end(kRawExtensions), extension) !=
         std::end(kRawExtensions);
}

nlohmann::json RawImage::describe() const {
  return {{"camera", camera},
          {"mosaic", mosaic},
          {"demosaic", demosaic},
          {"black_level", {black[0], black[1], black[2], black[3]}},
          {"white_level", white}};
}

cv::Size read_raw_size(const std::filesystem::path& path, RawDemosaic demosaic) {
  int data_error = -1;
  const RawHandle raw = open_raw(path, &data_error);
  return output_size(*raw, bins(*raw, demosaic));
}

namespace {

RawImage decode(const std::filesystem::path& path, RawDemosaic demosaic) {
  int data_error = -1;
  const RawHandle raw = open_raw(path, &data_error);
  const auto& idata = raw->imgdata.idata;
  if (idata.raw_count > 1 || idata.is_foveon)
    fail(
        "{}: a multi-frame or Foveon RAW file; only single-frame mosaic, monochrome and linear files are "
        "read",
        path.string());
  const bool binned = bins(*raw, demosaic);
  const cv::Size size = output_size(*raw, binned);
  if (size.width > kMaxImageSide || size.height > kMaxImageSide)
    fail("{}: decodes to {}x{}, larger than the {}x{} a stack may hold", path.string(), size.width,
         size.height, kMaxImageSide, kMaxImageSide);
  int rc = raw->unpack();
  if (rc != LIBRAW_SUCCESS) fail("{}: cannot decode the RAW data ({})", path.string(), libraw_strerror(rc));
  if (data_error >= 0) fail("{}: corrupt RAW data (at byte {})", path.string(), data_error);
  if (raw->is_sraw())
    fail("{}: an sRAW/mRAW file (white-balanced and resampled by the camera); shoot full-size RAW",
         path.string());

  RawImage out;
  out.camera = ascii_text(fmt::format("{} {}", idata.make, idata.model));
  const auto& colour = raw->imgdata.color;
  const BlackLevels black = black_levels(path, colour);
  for (int c = 0; c < 4; ++c)
    out.black[static_cast<std::size_t>(c)] = static_cast<double>(colour.black) + colour.cblack[c];
  out.white = colour.maximum;
  const auto& rawdata = raw->imgdata.rawdata;
  const bool bin = binned && rawdata.raw_image != nullptr;
  const std::string bayer = rawdata.raw_image != nullptr ? bayer_pattern(*raw) : std::string();
  if (!bayer.empty()) {
    // Each site's own level, pattern included: R, the first G, B, the second G.
    bool first_green = true;
    for (int site = 0; site < 4; ++site) {
      const int r = site / 2, c = site % 2;
      const char letter = idata.cdesc[raw->COLOR(r, c)];
      const std::size_t slot = letter == 'R' ? 0 : letter == 'B' ? 2 : first_green ? 1 : 3;
      if (letter == 'G') first_green = false;
      out.black[slot] = black.at(r, c, raw->COLOR(r, c));
    }
  }
  const double darkest = highest_black(colour, black);
  if (!(out.white > darkest))
    fail("{}: white level {} is not above the black level {}", path.string(), out.white, darkest);

  if (bin) {
    check_geometry(path, *raw, 1);
    out.mosaic = bayer;
    out.demosaic = "half";
    out.image = bin_bayer(*raw, black, out.white);
  } else if (rawdata.raw_image != nullptr && (!bayer.empty() || idata.filters == kXTrans)) {
    check_geometry(path, *raw, 1);
    out.mosaic = bayer.empty() ? "X-Trans" : bayer;
    out.demosaic = "full";
    out.image = demosaic_full(path, *raw);
    mark_clipped_neighbourhoods(*raw, out.white, out.image);
  } else if (rawdata.raw_image != nullptr && idata.filters == 0 && idata.colors == 1) {
    check_geometry(path, *raw, 1);
    out.mosaic = "monochrome";
    out.demosaic = "none";
    out.image = monochrome(*raw, black, out.white);
  } else if (rawdata.color3_image != nullptr || rawdata.color4_image != nullptr) {
    check_geometry(path, *raw, rawdata.color4_image != nullptr ? 4 : 3);
    out.mosaic = "linear";
    out.demosaic = "none";
    out.image = linear(*raw, black, out.white);
  } else {
    fail("{}: a RAW layout this reader does not take (colours '{}', filters {:#x}{})", path.string(),
         ascii_text(idata.cdesc), idata.filters, rawdata.float_image != nullptr ? ", floating point" : "");
  }
  if (out.image.size() != size)
    fail("{}: decoded to {}x{} where its header gives {}x{}", path.string(), out.image.cols, out.image.rows,
         size.width, size.height);
  if (data_error >= 0) fail("{}: corrupt RAW data (at byte {})", path.string(), data_error);
  return out;
}

}  // namespace

RawImage read_raw(const std::filesystem::path& path, RawDemosaic demosaic) {
  try {
    return decode(path, demosaic);
  } catch (const std::bad_alloc&) {
    fail("{}: too large to decode in the memory available", path.string());
  } catch (const cv::Exception& e) {
    fail("{}: cannot decode ({})", path.string(), e.what());
  }
}

}  // namespace lightstage::io
