#include "lightstage/host/surface/depth_prior.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/pfm.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace lightstage::surface {
namespace {

// OpenCV reads EXR through OpenEXR, but since 4.5.5 the codec is gated by the
// environment variable OPENCV_IO_ENABLE_OPENEXR (upstream builds default it to
// off; Debian 12's build to on), and OpenCV reads the variable only once, on
// the process's first EXR decode. So it is set here, in the one place this
// program means to decode EXR, before that first decode. A value the user set
// (e.g. 0, to keep OpenEXR away from untrusted files) is left alone: the load
// then fails with OpenCV's message naming the variable.
void enable_opencv_exr() {
  static const bool enabled = [] { return ::setenv("OPENCV_IO_ENABLE_OPENEXR", "1", 0) == 0; }();
  (void)enabled;
}

// What the EXR header says about the file (openexr.com, "OpenEXR File Layout"):
// enough to pick the depth channel and name what is wrong before decoding.
struct ExrChannel {
  std::string name;
  std::size_t name_offset = 0;  // of the name's first byte in the file
  std::int32_t pixel_type = 0;  // 0 UINT, 1 HALF, 2 FLOAT
  std::int32_t x_sampling = 1, y_sampling = 1;
};

struct ExrBox {
  std::int32_t x_min = 0, y_min = 0, x_max = -1, y_max = -1;
  bool operator==(const ExrBox&) const = default;
  std::int64_t width() const { return std::int64_t{x_max} - x_min + 1; }
  std::int64_t height() const { return std::int64_t{y_max} - y_min + 1; }
};

class ExrHeaderReader {
 public:
  ExrHeaderReader(const std::vector<std::uint8_t>& bytes, const std::string& file)
      : bytes_(bytes), file_(file) {}

  std::size_t position() const { return at_; }

  // A NUL-terminated string of at most 255 characters (long names: attribute
  // and channel names are limited to 255 bytes either way).
  std::string string() {
    std::string out;
    while (true) {
      need(1, "a name");
      const char ch = static_cast<char>(bytes_[at_++]);
      if (ch == '\0') return out;
      if (out.size() == 255) fail("{}: EXR header: a name longer than 255 bytes (corrupt file)", file_);
      out.push_back(ch);
    }
  }

  std::int32_t int32() {
    need(4, "a number");
    std::uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = (v << 8) | bytes_[at_ + static_cast<std::size_t>(i)];
    at_ += 4;
    return static_cast<std::int32_t>(v);
  }

  void skip(std::size_t n, const char* what) {
    need(n, what);
    at_ += n;
  }

  void need(std::size_t n, const char* what) const {
    if (bytes_.size() - at_ < n) fail("{}: EXR header ends inside {} (truncated file)", file_, what);
  }

 private:
  const std::vector<std::uint8_t>& bytes_;
  const std::string& file_;
  std::size_t at_ = 0;
};

struct ExrHeader {
  std::vector<ExrChannel> channels;
  ExrBox data_window, display_window;
};

ExrHeader read_exr_header(const std::vector<std::uint8_t>& bytes, const std::string& file) {
  ExrHeaderReader in(bytes, file);
  if (bytes.size() < 8 || bytes[0] != 0x76 || bytes[1] != 0x2f || bytes[2] != 0x31 || bytes[3] != 0x01)
    fail("{}: not an OpenEXR file (no EXR magic number)", file);
  in.skip(4, "the magic number");
  const auto version = static_cast<std::uint32_t>(in.int32());
  if ((version & 0xffu) != 2) fail("{}: EXR version {} is not supported (2 is)", file, version & 0xffu);
  if (version & 0x1800u)  // bit 11: deep data, bit 12: multi-part
    fail("{}: deep or multi-part EXR files are not read; write the depth as a single-part image", file);
  ExrHeader header;
  bool have_channels = false, have_data = false, have_display = false;
  while (true) {
    const std::string name = in.string();
    if (name.empty()) break;
    const std::string type = in.string();
    const std::int32_t size = in.int32();
    if (size < 0) fail("{}: EXR header: attribute '{}' has a negative size", file, name);
    in.need(static_cast<std::size_t>(size), "an attribute");
    const std::size_t end = in.position() + static_cast<std::size_t>(size);
    if (name == "channels" && type == "chlist") {
      have_channels = true;
      while (true) {
        if (in.position() >= end) fail("{}: EXR header: channel list is not terminated", file);
        ExrChannel channel;
        channel.name_offset = in.position();
        channel.name = in.string();
        if (channel.name.empty()) break;
        channel.pixel_type = in.int32();
        in.skip(4, "a channel");  // pLinear and three reserved bytes
        channel.x_sampling = in.int32();
        channel.y_sampling = in.int32();
        header.channels.push_back(std::move(channel));
      }
    } else if ((name == "dataWindow" || name == "displayWindow") && type == "box2i" && size == 16) {
      ExrBox& box = name == "dataWindow" ? header.data_window : header.display_window;
      (name == "dataWindow" ? have_data : have_display) = true;
      box.x_min = in.int32();
      box.y_min = in.int32();
      box.x_max = in.int32();
      box.y_max = in.int32();
    }
    if (in.position() != end) {
      if (in.position() > end) fail("{}: EXR header: attribute '{}' overruns its size", file, name);
      in.skip(end - in.position(), "an attribute");
    }
  }
  if (!have_channels) fail("{}: EXR header has no channel list", file);
  if (!have_data || !have_display) fail("{}: EXR header lacks its data or display window", file);
  return header;
}

std::string channel_names(const std::vector<ExrChannel>& channels) {
  std::string out;
  for (const auto& channel : channels) out += (out.empty() ? "" : ", ") + channel.name;
  return out.empty() ? "none" : out;
}

// A single-channel float EXR: the channel is named Y (what OpenCV and most
// image tools write for grey), Z (the OpenEXR convention for depth) or R;
// HALF or FLOAT, unsubsampled, the data window the whole (display) frame.
cv::Mat read_exr_depth(const std::filesystem::path& path, const cv::Size& expected) {
  const std::string file = path.string();
  std::vector<std::uint8_t> bytes;
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) fail("{}: cannot open for reading", file);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (in.bad()) fail("{}: read error", file);
  }
  const ExrHeader header = read_exr_header(bytes, file);
  if (header.channels.size() != 1)
    fail("{}: a depth EXR must have one channel (named Y, Z or R), this has {} ({})", file,
         header.channels.size(), channel_names(header.channels));
  const ExrChannel& channel = header.channels.front();
  if (channel.name != "Y" && channel.name != "Z" && channel.name != "R")
    fail("{}: EXR channel '{}': a depth channel must be named Y, Z or R", file, channel.name);
  if (channel.pixel_type != 1 && channel.pixel_type != 2)
    fail("{}: EXR channel '{}' is {}: depth must be HALF or FLOAT", file, channel.name,
         channel.pixel_type == 0 ? "UINT" : "of an unknown pixel type");
  if (channel.x_sampling != 1 || channel.y_sampling != 1)
    fail("{}: EXR channel '{}' is subsampled ({}x{}); depth must have a value per pixel", file, channel.name,
         channel.x_sampling, channel.y_sampling);
  if (!(header.data_window == header.display_window))
    fail("{}: EXR data window differs from the display window (a cropped image); write the whole frame",
         file);
  // Checked before decoding: OpenEXR allocates what the header asks for.
  if (header.data_window.width() != expected.width || header.data_window.height() != expected.height)
    fail("{}: depth prior is {}x{} but the images are {}x{}", file, header.data_window.width(),
         header.data_window.height(), expected.width, expected.height);
  // OpenCV decodes a lone Y channel as grey and knows no Z; R alone it would
  // widen to three channels. Either is renamed Y in memory (one byte, same
  // length: nothing else in the file moves) before decoding.
  bytes[channel.name_offset] = 'Y';
  enable_opencv_exr();
  cv::Mat image;
  try {
    image = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    fail("{}: cannot decode EXR channel '{}': {}", file, channel.name, e.what());
  }
  if (image.empty()) fail("{}: cannot decode EXR channel '{}' (corrupt file)", file, channel.name);
  if (image.type() != CV_32FC1 || image.size() != expected)
    fail("{}: EXR channel '{}' decoded to {}x{} of type {}, expected {}x{} floats", file, channel.name,
         image.cols, image.rows, image.type(), expected.width, expected.height);
  return image;
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
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
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
