#include "lightstage/host/surface/depth_prior.hpp"

#include "io/file_extension.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/exr.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/pfm.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace lightstage::surface {
namespace {

std::string channel_names(const std::vector<io::ExrChannel>& channels) {
  std::string out;
  for (const auto& channel : channels) out += (out.empty() ? "" : ", ") + channel.name;
  return out.empty() ? "none" : out;
}

// A single-channel float EXR: the channel is named Y (what OpenCV and most
// image tools write for grey), Z (the OpenEXR convention for depth) or R;
// HALF or FLOAT, unsubsampled, the data window the whole (display) frame.
cv::Mat read_exr_depth(const std::filesystem::path& path, const cv::Size& expected) {
  const std::string file = path.string();
  const io::ExrFile exr(path);
  const io::ExrHeader& header = exr.header();
  if (header.channels.size() != 1)
    fail("{}: a depth EXR must have one channel (named Y, Z or R), this has {} ({})", file,
         header.channels.size(), channel_names(header.channels));
  const io::ExrChannel& channel = header.channels.front();
  if (channel.name != "Y" && channel.name != "Z" && channel.name != "R")
    fail("{}: EXR channel '{}': a depth channel must be named Y, Z or R", file, channel.name);
  if (channel.type == io::ExrPixelType::kUint32)
    fail("{}: EXR channel '{}' is UINT: depth must be HALF or FLOAT", file, channel.name);
  if (channel.x_sampling != 1 || channel.y_sampling != 1)
    fail("{}: EXR channel '{}' is subsampled ({}x{}); depth must have a value per pixel", file, channel.name,
         channel.x_sampling, channel.y_sampling);
  if (header.cropped)
    fail("{}: EXR data window differs from the display window (a cropped image); write the whole frame",
         file);
  // Checked before decoding, so that only the expected pixels are allocated.
  if (header.size != expected)
    fail("{}: depth prior is {}x{} but the images are {}x{}", file, header.size.width, header.size.height,
         expected.width, expected.height);
  return exr.read({channel.name});
}

}  // namespace

void DepthPriorOptions::check() const {
  if (!(png_scale > 0) || !std::isfinite(png_scale))
    fail("depth prior: png scale must be positive, got {}", png_scale);
  if (!std::isfinite(png_offset)) fail("depth prior: png offset must be finite, got {}", png_offset);
}

DepthMap render_depth(const Mesh& mesh, const CameraModel& camera) {
  camera.check();
  const int rows = camera.size.height, cols = camera.size.width;
  DepthMap out;
  out.depth = cv::Mat::zeros(camera.size, CV_32FC1);
  out.valid = cv::Mat::zeros(camera.size, CV_8UC1);
  // Keep the nearest surface: the largest height (orthographic) or the smallest distance.
  const bool keep_larger = !camera.perspective_model();
  struct Projected {
    double col, row, depth;
    bool ok;
  };
  std::vector<Projected> projected(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    Projected& p = projected[i];
    p.ok = camera.project(mesh.vertices[i].cast<double>(), &p.col, &p.row, &p.depth) &&
           std::isfinite(p.col) && std::isfinite(p.row) && std::isfinite(p.depth);
  }
  for (const auto& t : mesh.triangles) {
    if (std::any_of(t.begin(), t.end(), [&](std::int32_t i) {
          return i < 0 || static_cast<std::size_t>(i) >= projected.size() ||
                 !projected[static_cast<std::size_t>(i)].ok;
        }))
      continue;
    const Projected& a = projected[static_cast<std::size_t>(t[0])];
    const Projected& b = projected[static_cast<std::size_t>(t[1])];
    const Projected& c = projected[static_cast<std::size_t>(t[2])];
    const double area = (b.col - a.col) * (c.row - a.row) - (c.col - a.col) * (b.row - a.row);
    if (std::abs(area) < 1e-12) continue;
    // Clamp in floating point before converting: a far-off vertex must not overflow an int.
    auto clamp_index = [](double v, int hi) {
      return static_cast<int>(std::clamp(v, -1.0, static_cast<double>(hi)));
    };
    const int c0 = std::max(0, clamp_index(std::ceil(std::min({a.col, b.col, c.col})), cols));
    const int c1 = std::min(cols - 1, clamp_index(std::floor(std::max({a.col, b.col, c.col})), cols));
    const int r0 = std::max(0, clamp_index(std::ceil(std::min({a.row, b.row, c.row})), rows));
    const int r1 = std::min(rows - 1, clamp_index(std::floor(std::max({a.row, b.row, c.row})), rows));
    for (int r = r0; r <= r1; ++r) {
      for (int col = c0; col <= c1; ++col) {
        // Barycentric coordinates of the pixel centre (col, row).
        const double wa = ((b.col - col) * (c.row - r) - (c.col - col) * (b.row - r)) / area;
        const double wb = ((c.col - col) * (a.row - r) - (a.col - col) * (c.row - r)) / area;
        const double wc = 1.0 - wa - wb;
        if (wa < -1e-9 || wb < -1e-9 || wc < -1e-9) continue;
        // Perspective: 1/d is affine in the image; orthographic: z is.
        const double d = camera.perspective_model() ? 1.0 / (wa / a.depth + wb / b.depth + wc / c.depth)
                                                    : wa * a.depth + wb * b.depth + wc * c.depth;
        if (!std::isfinite(d)) continue;
        float& dst = out.depth.at<float>(r, col);
        std::uint8_t& v = out.valid.at<std::uint8_t>(r, col);
        if (!v || (keep_larger ? d > dst : d < dst)) {
          dst = static_cast<float>(d);
          v = 255;
        }
      }
    }
  }
  return out;
}

DepthMap load_depth_prior(const std::filesystem::path& path, const CameraModel& camera,
                          const DepthPriorOptions& options) {
  options.check();
  camera.check();
  const std::string ext = io::lower_extension(path);
  DepthMap out;
  if (ext == ".ply") {
    out = render_depth(read_ply(path), camera);
  } else if (ext == ".png" || ext == ".pfm" || ext == ".exr") {
    const cv::Mat image = ext == ".exr" ? read_exr_depth(path, camera.size) : io::read_image(path);
    if (image.channels() != 1)
      fail("{}: a depth prior must have one channel, this has {}", path.string(), image.channels());
    if (ext == ".png" && image.depth() != CV_16U)
      fail("{}: a depth PNG must be 16-bit (8 bits cannot hold depth)", path.string());
    if (image.size() != camera.size)
      fail("{}: depth prior is {}x{} but the images are {}x{}", path.string(), image.cols, image.rows,
           camera.size.width, camera.size.height);
    out.depth = cv::Mat::zeros(camera.size, CV_32FC1);
    out.valid = cv::Mat::zeros(camera.size, CV_8UC1);
    for (int r = 0; r < image.rows; ++r) {
      for (int c = 0; c < image.cols; ++c) {
        double d = 0;
        if (ext == ".png") {
          const std::uint16_t dn = image.at<std::uint16_t>(r, c);
          if (dn == 0) continue;
          d = dn * options.png_scale + options.png_offset;
        } else {
          d = image.at<float>(r, c);
          if (d == 0 || !std::isfinite(d)) continue;
        }
        if (camera.perspective_model() && !(d > 0)) continue;
        out.depth.at<float>(r, c) = static_cast<float>(d);
        out.valid.at<std::uint8_t>(r, c) = 255;
      }
    }
  } else {
    fail("{}: unknown depth prior format '{}' (use .png, .pfm, .exr or .ply)", path.string(), ext);
  }
  if (cv::countNonZero(out.valid) == 0) fail("{}: the depth prior holds no valid depth", path.string());
  return out;
}

}  // namespace lightstage::surface
