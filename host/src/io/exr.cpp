#include "lightstage/host/io/exr.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/row_reader.hpp"
#include "lightstage/host/io/row_writer.hpp"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfCompression.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfTileDescription.h>
#include <OpenEXR/ImfVersion.h>
#include <OpenEXR/ImfXdr.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <exception>
#include <fstream>
#include <iterator>
#include <set>
#include <utility>

namespace lightstage::io {

// The file's bytes as an OpenEXR input stream. A read past the end is
// remembered, so that a failure can be told apart as a truncated file.
struct ExrFile::Bytes : Imf::IStream {
  Bytes(std::string bytes, const std::string& name) : Imf::IStream(name.c_str()), data(std::move(bytes)) {}

  bool read(char c[], int n) override {
    if (n < 0 || static_cast<std::uint64_t>(n) > data.size() - std::min<std::uint64_t>(at, data.size())) {
      ran_out = true;
      throw Iex::InputExc("unexpected end of file");
    }
    std::memcpy(c, data.data() + at, static_cast<std::size_t>(n));
    at += static_cast<std::uint64_t>(n);
    return at < data.size();
  }
  std::uint64_t tellg() override { return at; }
  void seekg(std::uint64_t pos) override { at = pos; }

  std::string data;
  std::uint64_t at = 0;
  bool ran_out = false;
};

namespace {

ExrPixelType pixel_type(Imf::PixelType type) {
  switch (type) {
    case Imf::UINT:
      return ExrPixelType::kUint32;
    case Imf::HALF:
      return ExrPixelType::kHalf;
    default:
      return ExrPixelType::kFloat32;
  }
}

std::string quoted_list(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& name : names) out += (out.empty() ? "'" : ", '") + name + "'";
  return out;
}

std::string read_whole_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("{}: cannot open for reading", path.string());
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) fail("{}: read error", path.string());
  return bytes;
}

// What a parsed header says, within the limits above: the pixel count caps an
// image decoded whole (`whole`), not one read a band of rows at a time.
ExrHeader describe(const Imf::Header& header, bool tiled, const std::string& name, bool whole) {
  ExrHeader out;
  const Imath::Box2i data = header.dataWindow();
  const std::int64_t width = std::int64_t{data.max.x} - data.min.x + 1;
  const std::int64_t height = std::int64_t{data.max.y} - data.min.y + 1;
  if (width < 1 || height < 1 || width > kExrMaxSide || height > kExrMaxSide ||
      (whole && width * height > kExrMaxPixels))
    fail("{}: EXR image is {}x{}; at most {} pixels, {} a side, are read", name, width, height, kExrMaxPixels,
         kExrMaxSide);
  out.size = cv::Size(static_cast<int>(width), static_cast<int>(height));
  out.cropped = data != header.displayWindow();
  out.tiled = tiled;
  if (tiled) {
    // OpenEXR sizes its tile-offset tables from the header: bound the tile count too.
    const Imf::TileDescription& tiles = header.tileDescription();
    const std::int64_t count =
        ((width + tiles.xSize - 1) / tiles.xSize) * ((height + tiles.ySize - 1) / tiles.ySize);
    if (count > (std::int64_t{1} << 20))
      fail("{}: EXR tiles of {}x{} make {} tiles for a {}x{} image; use larger tiles or scan lines", name,
           tiles.xSize, tiles.ySize, count, width, height);
  }
  for (auto it = header.channels().begin(); it != header.channels().end(); ++it)
    out.channels.push_back(
        {it.name(), pixel_type(it.channel().type), it.channel().xSampling, it.channel().ySampling});
  return out;
}

// The channels asked for (1 to 4) are there once each, a value per pixel, in a whole frame.
void check_channels(const ExrHeader& header, const std::string& name,
                    const std::vector<std::string>& channels) {
  if (channels.empty() || channels.size() > 4)
    fail("{}: cannot read {} EXR channels at once (1 to 4)", name, channels.size());
  std::vector<std::string> present;
  for (const auto& channel : header.channels) present.push_back(channel.name);
  std::set<std::string> seen;
  for (const auto& wanted : channels) {
    if (!seen.insert(wanted).second) fail("{}: EXR channel '{}' asked for twice", name, wanted);
    const auto it = std::find_if(header.channels.begin(), header.channels.end(),
                                 [&](const ExrChannel& channel) { return channel.name == wanted; });
    if (it == header.channels.end())
      fail("{}: EXR has no channel '{}' (it has {})", name, wanted,
           present.empty() ? std::string("none") : quoted_list(present));
    if (it->x_sampling != 1 || it->y_sampling != 1)
      fail("{}: EXR channel '{}' is subsampled ({}x{}); a value per pixel is needed", name, wanted,
           it->x_sampling, it->y_sampling);
  }
  if (header.cropped)
    fail("{}: EXR data window differs from the display window (a cropped image); write the whole frame",
         name);
}

// A frame buffer putting `channels` of the data window's rows from `first_row` into `out` (CV_32FC(n)).
Imf::FrameBuffer float_slices(const std::vector<std::string>& channels, const Imath::Box2i& data,
                              int first_row, cv::Mat& out) {
  Imath::Box2i window = data;
  window.min.y = data.min.y + first_row;
  Imf::FrameBuffer frame;
  const auto n = channels.size();
  for (std::size_t i = 0; i < n; ++i)
    frame.insert(channels[i],
                 Imf::Slice::Make(Imf::FLOAT, out.ptr<float>() + i, window, sizeof(float) * n, out.step[0]));
  return frame;
}

// Rows decoded from the file on disk as they are asked for (OpenEXR keeps its own buffers).
class ExrRows final : public RowReader {
 public:
  ExrRows(const std::filesystem::path& path, std::unique_ptr<Imf::InputFile> file, cv::Size size,
          std::vector<std::string> channels)
      : RowReader(path, size, CV_MAKETYPE(CV_32F, static_cast<int>(channels.size()))),
        file_(std::move(file)),
        channels_(std::move(channels)) {}

 private:
  void read_rows(int y0, int rows, cv::Mat& out) override {
    try {
      const Imath::Box2i& data = file_->header().dataWindow();
      file_->setFrameBuffer(float_slices(channels_, data, y0, out));
      file_->readPixels(data.min.y + y0, data.min.y + y0 + rows - 1);
    } catch (const std::exception& e) {
      fail("{}: cannot decode EXR rows {} to {}: {}", path().string(), y0, y0 + rows - 1, e.what());
    }
  }

  std::unique_ptr<Imf::InputFile> file_;
  std::vector<std::string> channels_;
};

}  // namespace

const char* to_string(ExrPixelType type) {
  switch (type) {
    case ExrPixelType::kUint32:
      return "UINT";
    case ExrPixelType::kHalf:
      return "HALF";
    case ExrPixelType::kFloat32:
      return "FLOAT";
  }
  return "?";
}

ExrFile::ExrFile(const std::filesystem::path& path) : ExrFile(read_whole_file(path), path.string()) {}

ExrFile::ExrFile(std::string bytes, std::string name)
    : name_(std::move(name)), bytes_(std::make_unique<Bytes>(std::move(bytes), name_)) {
  parse_header();
}

ExrFile::~ExrFile() = default;
ExrFile::ExrFile(ExrFile&&) noexcept = default;
ExrFile& ExrFile::operator=(ExrFile&&) noexcept = default;

void ExrFile::parse_header() {
  Bytes& in = *bytes_;
  if (in.data.size() < 4 || !Imf::isImfMagic(in.data.data()))
    fail("{}: not an OpenEXR file (no EXR magic number)", name_);
  Imf::Header header;
  int version = 0;
  try {
    in.seekg(4);
    Imf::Xdr::read<Imf::StreamIO>(in, version);
    if (Imf::getVersion(version) != Imf::EXR_VERSION)
      fail("{}: EXR version {} is not supported ({} is)", name_, Imf::getVersion(version), Imf::EXR_VERSION);
    if (Imf::isMultiPart(version) || Imf::isNonImage(version))
      fail("{}: deep or multi-part EXR files are not read; write a single-part flat image", name_);
    header.readFrom(in, version);
    header.sanityCheck(Imf::isTiled(version));
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    if (in.ran_out) fail("{}: EXR header ends inside the file (truncated file)", name_);
    fail("{}: EXR header: {}", name_, e.what());
  }
  header_ = describe(header, Imf::isTiled(version), name_, /*whole=*/true);
}

cv::Mat ExrFile::read(const std::vector<std::string>& channels) const {
  check_channels(header_, name_, channels);

  const int n = static_cast<int>(channels.size());
  cv::Mat image(header_.size, CV_MAKETYPE(CV_32F, n));
  Bytes& in = *bytes_;
  in.ran_out = false;
  try {
    in.seekg(0);
    Imf::InputFile file(in);
    const Imath::Box2i& data = file.header().dataWindow();
    file.setFrameBuffer(float_slices(channels, data, 0, image));
    file.readPixels(data.min.y, data.max.y);
  } catch (const std::exception& e) {
    fail("{}: cannot decode EXR channel{} {}: {}{}", name_, n == 1 ? "" : "s", quoted_list(channels),
         e.what(), in.ran_out ? " (truncated file)" : "");
  }
  return image;
}

cv::Mat read_exr(const std::filesystem::path& path, const std::vector<std::string>& channels) {
  return ExrFile(path).read(channels);
}

std::unique_ptr<RowReader> open_exr_rows(const std::filesystem::path& path,
                                         const std::vector<std::string>& channels) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) fail("{}: no such file", path.string());
  std::unique_ptr<Imf::InputFile> file;
  ExrHeader header;
  try {
    file = std::make_unique<Imf::InputFile>(path.c_str());
    if (!file->isComplete()) fail("{}: EXR ends before its last scan line (truncated file)", path.string());
    header = describe(file->header(), file->header().hasTileDescription(), path.string(), /*whole=*/false);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    fail("{}: EXR header: {}", path.string(), e.what());
  }
  check_channels(header, path.string(), channels);
  return std::make_unique<ExrRows>(path, std::move(file), header.size, channels);
}

void write_exr(const std::filesystem::path& path, const cv::Mat& image,
               const std::vector<std::string>& channels) {
  const auto writer = open_exr_writer(path, image.size(), image.type(), channels);
  writer->write(image);
  writer->commit();
}

}  // namespace lightstage::io
