// EXR scanlines through OpenEXR, as write_exr writes the whole image: float
// channels, uncompressed, rows in increasing y; the line offset table is
// written when the file is complete. Uncompressed: ZIP made float maps only
// about a fifth smaller for more CPU than their solve (docs/stack-format.md).
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/row_writer.hpp"
#include "util/atomic_file.hpp"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfCompression.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfOutputFile.h>

#include <cstdint>
#include <exception>
#include <memory>
#include <set>
#include <string_view>

namespace lightstage::io {
namespace {

// OpenEXR's output stream over the temporary file (it seeks back to write the offsets).
class TemporaryFileStream final : public Imf::OStream {
 public:
  explicit TemporaryFileStream(util::TemporaryFile& file)
      : Imf::OStream(file.target().c_str()), file_(file) {}
  void write(const char c[], int n) override {
    file_.write_at(at_, std::string_view(c, static_cast<std::size_t>(n)));
    at_ += static_cast<std::uint64_t>(n);
  }
  std::uint64_t tellp() override { return at_; }
  void seekp(std::uint64_t pos) override { at_ = pos; }

 private:
  util::TemporaryFile& file_;
  std::uint64_t at_ = 0;
};

class ExrRowWriter final : public RowWriter {
 public:
  ExrRowWriter(const std::filesystem::path& path, cv::Size size, int type, std::vector<std::string> channels)
      : RowWriter(path, size, type), file_(path), stream_(file_), channels_(std::move(channels)) {
    guarded([&] {
      Imf::Header header(size.width, size.height);
      header.compression() = Imf::NO_COMPRESSION;
      for (const auto& name : channels_) header.channels().insert(name, Imf::Channel(Imf::FLOAT));
      exr_ = std::make_unique<Imf::OutputFile>(stream_, header);
    });
  }

 private:
  void write_rows(const cv::Mat& rows, int y0) override {
    guarded([&] {
      const std::size_t n = channels_.size();
      // The slices address pixel (x, y) of the whole image; only rows [y0, y0 + rows) are read.
      char* origin = const_cast<char*>(rows.ptr<char>()) -
                     static_cast<std::ptrdiff_t>(y0) * static_cast<std::ptrdiff_t>(rows.step[0]);
      Imf::FrameBuffer frame;
      for (std::size_t i = 0; i < n; ++i)
        frame.insert(channels_[i],
                     Imf::Slice(Imf::FLOAT, origin + i * sizeof(float), n * sizeof(float), rows.step[0]));
      exr_->setFrameBuffer(frame);
      exr_->writePixels(rows.rows);
    });
  }
  void finish() override {
    guarded([&] { exr_.reset(); });  // writes the line offset table
    file_.commit();
  }
  template <typename F>
  void guarded(F&& f) {
    try {
      f();
    } catch (const Error&) {
      throw;  // the file's own failure (a full disk), already named
    } catch (const std::exception& e) {
      fail("{}: cannot write as EXR: {}", path().string(), e.what());
    }
  }

  util::TemporaryFile file_;
  TemporaryFileStream stream_;
  std::vector<std::string> channels_;
  std::unique_ptr<Imf::OutputFile> exr_;
};

}  // namespace

std::unique_ptr<RowWriter> open_exr_writer(const std::filesystem::path& path, cv::Size size, int type,
                                           const std::vector<std::string>& channels) {
  if (type != CV_32FC1 && type != CV_32FC3)
    fail("{}: cannot write as EXR: expected CV_32FC1 or CV_32FC3, got {}", path.string(),
         cv::typeToString(type));
  if (channels.size() != static_cast<std::size_t>(CV_MAT_CN(type)))
    fail("{}: cannot write as EXR: {} channel name(s) for {} channel(s)", path.string(), channels.size(),
         CV_MAT_CN(type));
  std::set<std::string> seen;
  for (const auto& name : channels) {
    if (name.empty() || name.size() > 255)
      fail("{}: cannot write as EXR: channel name '{}' (1 to 255 bytes)", path.string(), name);
    if (!seen.insert(name).second)
      fail("{}: cannot write as EXR: channel name '{}' repeated", path.string(), name);
  }
  return std::make_unique<ExrRowWriter>(path, size, type, channels);
}

}  // namespace lightstage::io
