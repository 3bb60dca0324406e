#include "lightstage/host/radiometry.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/huge_pages.hpp"
#include "lightstage/common/lane_sort.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/common/simd_clones.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <optional>

namespace lightstage {
namespace {

constexpr double kRed = 0.2989, kGreen = 0.5870, kBlue = 0.1140;

double full_scale(int depth) { return depth == CV_16U ? 65535.0 : depth == CV_8U ? 255.0 : 1.0; }

double default_saturation(int depth) {
  return depth == CV_16U ? 65535.0 : depth == CV_8U ? 255.0 : std::numeric_limits<double>::infinity();
}

// What one frame's conversion needs, worked out once per frame.
struct FrameConstants {
  const cv::Mat* image = nullptr;
  const cv::Mat* dark = nullptr;  // CV_32F, the image's channels; null = subtract `black`
  double scale = 1, saturation = 0, black = 0;
  Vec3 intensity = Vec3::Ones();  // r, g, b
  double grey_intensity = 1;
  // 1 / (scale · intensity): a product per value instead of two quotients.
  Vec3 gain = Vec3::Ones();
  double grey_gain = 1;
};

FrameConstants frame_constants(const Frame& frame, const cv::Mat* dark) {
  FrameConstants k;
  k.image = &frame.image;
  k.dark = dark;
  k.scale = full_scale(frame.image.depth());
  k.saturation =
      frame.saturation_level > 0 ? frame.saturation_level : default_saturation(frame.image.depth());
  k.black = frame.black_level;
  k.intensity = frame.light_intensity;
  // Grey images: divide by the grey of the light.
  // The BT.601 weights sum to 0.9999: normalise so that a grey light of 1 divides by exactly 1.
  k.grey_intensity =
      (kRed * k.intensity.x() + kGreen * k.intensity.y() + kBlue * k.intensity.z()) / (kRed + kGreen + kBlue);
  k.gain = (k.scale * k.intensity).cwiseInverse();
  k.grey_gain = 1.0 / (k.scale * k.grey_intensity);
  return k;
}

// Converts pixels [begin, end) of one frame into column `column`.
// Colour frames also leave each pixel's linear (r, g, b), unclamped, in
// `rgb` at ((p − begin) · frame_count + column) · 3.
template <typename T, bool kColour>
void convert_frame(const FrameConstants& k, const std::vector<cv::Point>& pixels, std::size_t begin,
                   std::size_t end, bool clamp_to_one, Eigen::Index column, ObservationMatrix& values,
                   FlagMatrix& saturated, float* rgb, std::size_t frame_count) {
  const cv::Mat& image = *k.image;
  const double saturation = k.saturation;
  constexpr int kChannels = kColour ? 3 : 1;
  const double scalar_black[3] = {k.black, k.black, k.black};
  for (std::size_t p = begin; p < end; ++p) {
    const T* px = image.ptr<T>(pixels[p].y) + pixels[p].x * kChannels;
    // The dark frame's pixel, or the scalar black level in every channel.
    double black[3] = {scalar_black[0], scalar_black[1], scalar_black[2]};
    if (k.dark != nullptr) {
      const float* d = k.dark->ptr<float>(pixels[p].y) + pixels[p].x * kChannels;
      for (int c = 0; c < kChannels; ++c) black[c] = static_cast<double>(d[c]);
    }
    double value = 0;
    bool clipped = false;
    if constexpr (kColour) {
      // BGR in memory.
      const double b = static_cast<double>(px[0]), g = static_cast<double>(px[1]),
                   r = static_cast<double>(px[2]);
      clipped = b >= saturation || g >= saturation || r >= saturation;
      const double red = (r - black[2]) * k.gain.x();
      const double green = (g - black[1]) * k.gain.y();
      const double blue = (b - black[0]) * k.gain.z();
      value = kRed * red + kGreen * green + kBlue * blue;
      float* out = rgb + ((p - begin) * frame_count + static_cast<std::size_t>(column)) * 3;
      out[0] = static_cast<float>(red);
      out[1] = static_cast<float>(green);
      out[2] = static_cast<float>(blue);
    } else {
      const double v = static_cast<double>(px[0]);
      clipped = v >= saturation;
      value = (v - black[0]) * k.grey_gain;
    }
    if (clamp_to_one) value = std::min(value, 1.0);
    const auto row = static_cast<Eigen::Index>(p);
    values(row, column) = static_cast<float>(value);
    saturated(row, column) = clipped;
  }
}

// Pixels converted together, every frame in turn: their rows of the
// (row-major) matrices, 96 images × 5 bytes × 256 ≈ 120 kB, stay in cache
// while each frame's column is filled in. Converting a whole frame at a time
// instead writes one value per cache line across the full matrices.
constexpr std::size_t kPixelBlock = 256;

// One pixel's grey and colour ratios in frames [0, n) from their linear
// (r, g, b) at rgb + frame · 3: grey[frame], ratios[channel · n + frame], each
// channel over the grey (over 1 where the grey is not positive: such a frame is
// never kept). Every frame at once, so that the divisions take vector lanes;
// the pixel's kept frames are picked after.
LIGHTSTAGE_SIMD_CLONES
void frame_ratios(const float* rgb, std::size_t n, double* grey, float* ratios) {
  // Four frames to a vector: GCC 12 at -O2 leaves the plain loop scalar.
  using Doubles = double __attribute__((vector_size(4 * sizeof(double)), aligned(4 * sizeof(double))));
  using Floats = float __attribute__((vector_size(4 * sizeof(float))));
  const Doubles zero{}, one = zero + 1.0;
  std::size_t j = 0;
  for (; j + 4 <= n; j += 4) {
    const float* v = rgb + j * 3;
    const Doubles channels[3] = {
        {v[0], v[3], v[6], v[9]}, {v[1], v[4], v[7], v[10]}, {v[2], v[5], v[8], v[11]}};
    const Doubles y = kRed * channels[0] + kGreen * channels[1] + kBlue * channels[2];
    std::memcpy(grey + j, &y, sizeof y);
    const Doubles over = y > zero ? y : one;
    for (std::size_t c = 0; c < 3; ++c) {
      const Floats ratio = __builtin_convertvector(channels[c] / over, Floats);
      std::memcpy(ratios + c * n + j, &ratio, sizeof ratio);
    }
  }
  for (; j < n; ++j) {
    const float* v = rgb + j * 3;
    const double y = kRed * v[0] + kGreen * v[1] + kBlue * v[2];
    grey[j] = y;
    const double over = y > 0 ? y : 1.0;
    for (std::size_t c = 0; c < 3; ++c) ratios[c * n + j] = static_cast<float>(v[c] / over);
  }
}

// The chroma (radiometry.hpp) of LaneSort::kLanes pixels at a time from
// their frames' linear (r, g, b): each pixel's ratios fill one lane, and the
// three channels' medians come from one sort of each.
class ChromaLanes {
 public:
  static constexpr std::size_t kLanes = LaneSort::kLanes;

  explicit ChromaLanes(std::size_t frame_count)
      : frame_count_(frame_count),
        sort_(frame_count),
        stride_(sort_.slots(frame_count) * kLanes),
        ratios_(3 * stride_),
        grey_(frame_count),
        frame_ratios_(3 * frame_count) {}

  // Pixels [0, count), count ≤ kLanes: rgb at (pixel · frame_count + frame) · 3,
  // saturated at pixel · frame_count + frame; chroma (r, g, b) to out + pixel · 3.
  void compute(const float* rgb, const bool* saturated, std::size_t count, float* out) {
    std::array<std::size_t, kLanes> lengths{};
    for (std::size_t lane = 0; lane < count; ++lane)
      lengths[lane] = fill_lane(rgb + lane * frame_count_ * 3, saturated + lane * frame_count_, lane);
    const std::size_t slots = sort_.slots(*std::max_element(lengths.begin(), lengths.end()));
    for (std::size_t lane = 0; lane < kLanes; ++lane)
      for (std::size_t i = lengths[lane]; i < slots; ++i)
        for (int c = 0; c < 3; ++c) ratios_[c * stride_ + i * kLanes + lane] = kPadding;
    for (int c = 0; c < 3; ++c) sort_.sort(ratios_.data() + c * stride_, slots);
    for (std::size_t lane = 0; lane < count; ++lane) {
      float* chroma = out + lane * 3;
      const std::size_t length = lengths[lane];
      Eigen::RowVector3d median;
      for (int c = 0; c < 3; ++c)
        median[c] = length == 0 ? 0.0 : std::max(0.0f, ratios_[c * stride_ + length / 2 * kLanes + lane]);
      const double median_grey = kRed * median[0] + kGreen * median[1] + kBlue * median[2];
      // Never lit, or lit to no colour: neutral.
      for (int c = 0; c < 3; ++c)
        chroma[c] = median_grey > 0 ? static_cast<float>(median[c] / median_grey) : 1.0f;
    }
  }

 private:
  static constexpr float kPadding = std::numeric_limits<float>::infinity();

  // One pixel's ratios, channel by channel, into `lane`; returns how many.
  std::size_t fill_lane(const float* rgb, const bool* saturated, std::size_t lane) {
    frame_ratios(rgb, frame_count_, grey_.data(), frame_ratios_.data());
    double brightest = 0;
    for (std::size_t j = 0; j < frame_count_; ++j)
      if (!saturated[j]) brightest = std::max(brightest, grey_[j]);
    if (!(brightest > 0)) return 0;
    std::size_t length = 0;
    for (std::size_t j = 0; j < frame_count_; ++j) {
      if (saturated[j] || !(grey_[j] >= kChromaMinShare * brightest)) continue;
      for (std::size_t c = 0; c < 3; ++c)
        ratios_[c * stride_ + length * kLanes + lane] = frame_ratios_[c * frame_count_ + j];
      ++length;
    }
    return length;
  }

  std::size_t frame_count_;
  LaneSort sort_;
  std::size_t stride_;               // one channel's values
  std::vector<float> ratios_;        // [channel][slot][lane]
  std::vector<double> grey_;         // a pixel's, [frame]
  std::vector<float> frame_ratios_;  // a pixel's, [channel][frame]
};

template <typename T, bool kColour>
void convert_pixels(const std::vector<FrameConstants>& frames, const std::vector<cv::Point>& pixels,
                    std::size_t begin, std::size_t end, bool clamp_to_one, Observations& obs) {
  std::vector<float> rgb(kColour ? kPixelBlock * frames.size() * 3 : 0);
  std::optional<ChromaLanes> chroma;
  if constexpr (kColour) chroma.emplace(frames.size());
  for (std::size_t block = begin; block < end; block += kPixelBlock) {
    const std::size_t block_end = std::min(end, block + kPixelBlock);
    for (std::size_t j = 0; j < frames.size(); ++j)
      convert_frame<T, kColour>(frames[j], pixels, block, block_end, clamp_to_one,
                                static_cast<Eigen::Index>(j), obs.intensities, obs.saturated, rgb.data(),
                                frames.size());
    if constexpr (kColour) {
      for (std::size_t p = block; p < block_end; p += ChromaLanes::kLanes) {
        const auto row = static_cast<Eigen::Index>(p);
        chroma->compute(rgb.data() + (p - block) * frames.size() * 3, obs.saturated.row(row).data(),
                        std::min(ChromaLanes::kLanes, block_end - p), obs.chroma.row(row).data());
      }
    }
  }
}

template <typename T>
void convert_pixels(const std::vector<FrameConstants>& frames, bool colour,
                    const std::vector<cv::Point>& pixels, std::size_t begin, std::size_t end,
                    bool clamp_to_one, Observations& obs) {
  if (colour)
    convert_pixels<T, true>(frames, pixels, begin, end, clamp_to_one, obs);
  else
    convert_pixels<T, false>(frames, pixels, begin, end, clamp_to_one, obs);
}

}  // namespace

void RadiometryOptions::check() const {
  if (threads < 0) fail("RadiometryOptions.threads: must be 0 (automatic) or positive, got {}", threads);
}

Observations make_observations(const ImageStack& stack, const RadiometryOptions& options) {
  options.check();
  if (stack.frames.empty()) fail("radiometry: the stack has no frames");
  const cv::Mat& first = stack.frames.front().image;
  if (first.empty()) fail("radiometry: frame 0 ({}) has no image", stack.frames.front().filename);
  const int depth = first.depth();
  if ((depth != CV_8U && depth != CV_16U && depth != CV_32F) ||
      (first.channels() != 1 && first.channels() != 3)) {
    fail("radiometry: frame 0 ({}): unsupported pixel type {}", stack.frames.front().filename, first.type());
  }
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    const Frame& frame = stack.frames[i];
    if (frame.image.size() != first.size() || frame.image.type() != first.type()) {
      fail("radiometry: frame {} ({}) differs in size or type from frame 0", i, frame.filename);
    }
    if (!(frame.light_intensity.array() > 0).all()) {
      fail("radiometry: frame {} ({}): light intensity must be positive", i, frame.filename);
    }
    if (!frame.dark.empty() &&
        (frame.dark.size() != first.size() || frame.dark.channels() != first.channels() ||
         (frame.dark.depth() != CV_8U && frame.dark.depth() != CV_16U && frame.dark.depth() != CV_32F))) {
      fail("radiometry: frame {} ({}): dark frame {} is type {} of {}x{}, the images are type {} of {}x{}", i,
           frame.filename, frame.dark_file, frame.dark.type(), frame.dark.cols, frame.dark.rows, first.type(),
           first.cols, first.rows);
    }
  }
  if (!stack.mask.empty() && (stack.mask.type() != CV_8UC1 || stack.mask.size() != first.size())) {
    fail("radiometry: mask must be CV_8UC1 of {}x{}, got type {} of {}x{}", first.cols, first.rows,
         stack.mask.type(), stack.mask.cols, stack.mask.rows);
  }

  Observations obs;
  obs.size = first.size();
  obs.mask = cv::Mat(first.size(), CV_8UC1, cv::Scalar::all(0));
  for (int y = 0; y < first.rows; ++y) {
    const auto* in = stack.mask.empty() ? nullptr : stack.mask.ptr<std::uint8_t>(y);
    auto* out = obs.mask.ptr<std::uint8_t>(y);
    for (int x = 0; x < first.cols; ++x) {
      if (in == nullptr || in[x] != 0) {
        obs.pixels.emplace_back(x, y);
        out[x] = 255;
      }
    }
  }
  const auto images = static_cast<Eigen::Index>(stack.frames.size());
  const auto rows = static_cast<Eigen::Index>(obs.pixels.size());
  obs.intensities.resize(rows, images);
  obs.saturated.resize(rows, images);
  advise_huge_pages(obs.intensities.data(), static_cast<std::size_t>(obs.intensities.size()) * sizeof(float));
  advise_huge_pages(obs.saturated.data(), static_cast<std::size_t>(obs.saturated.size()));
  obs.lights.resize(images, 3);
  for (Eigen::Index j = 0; j < images; ++j) {
    obs.lights.row(j) = stack.frames[static_cast<std::size_t>(j)].light_direction.normalized().transpose();
  }
  // Dark frames as float, converted once each (frames of one exposure share one).
  std::map<const void*, cv::Mat> darks;
  for (const Frame& frame : stack.frames) {
    if (frame.dark.empty() || darks.count(frame.dark.data)) continue;
    frame.dark.convertTo(darks[frame.dark.data], CV_MAKETYPE(CV_32F, frame.dark.channels()));
  }
  std::vector<FrameConstants> frames;
  frames.reserve(stack.frames.size());
  for (const Frame& frame : stack.frames)
    frames.push_back(frame_constants(frame, frame.dark.empty() ? nullptr : &darks.at(frame.dark.data)));
  const bool colour = first.channels() == 3;
  if (colour) obs.chroma.resize(rows, 3);
  parallel_chunks(obs.pixels.size(), options.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    switch (depth) {
      case CV_8U:
        convert_pixels<std::uint8_t>(frames, colour, obs.pixels, begin, end, options.clamp_to_one, obs);
        break;
      case CV_16U:
        convert_pixels<std::uint16_t>(frames, colour, obs.pixels, begin, end, options.clamp_to_one, obs);
        break;
      default:
        convert_pixels<float>(frames, colour, obs.pixels, begin, end, options.clamp_to_one, obs);
        break;
    }
  });
  return obs;
}

cv::Mat chroma_image(const Observations& obs, const cv::Mat& solved) {
  if (obs.chroma.rows() == 0) return {};
  if (obs.chroma.rows() != static_cast<Eigen::Index>(obs.pixels.size()))
    fail("radiometry: {} chroma rows for {} pixels", obs.chroma.rows(), obs.pixels.size());
  if (!solved.empty() && (solved.type() != CV_8UC1 || solved.size() != obs.size))
    fail("radiometry: the solved map is type {} of {}x{}, the observations {}x{}", solved.type(), solved.cols,
         solved.rows, obs.size.width, obs.size.height);
  cv::Mat out(obs.size, CV_32FC3, cv::Scalar::all(0));
  for (std::size_t p = 0; p < obs.pixels.size(); ++p) {
    const cv::Point at = obs.pixels[p];
    if (!solved.empty() && solved.at<std::uint8_t>(at) == 0) continue;
    const auto row = static_cast<Eigen::Index>(p);
    out.at<cv::Vec3f>(at) = cv::Vec3f(obs.chroma(row, 2), obs.chroma(row, 1), obs.chroma(row, 0));
  }
  return out;
}

}  // namespace lightstage
