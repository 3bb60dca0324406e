// Rows of a file that decodes only whole, kept in an unlinked temporary file.
#include "io/row_readers.hpp"
#include "lightstage/host/io/temporary_rows.hpp"

namespace lightstage::io {
namespace {

class SpilledRows final : public RowReader {
 public:
  SpilledRows(const std::filesystem::path& path, const cv::Mat& image)
      : RowReader(path, image.size(), image.type()),
        rows_(path.string(), image.cols, image.type(), image.rows) {
    rows_.append(image);
  }
  bool decoded_whole() const override { return true; }

 private:
  void read_rows(int y0, int rows, cv::Mat& out) override {
    rows_.read(y0, rows, out);  // `out` is allocated to the band: the rows land in it
  }

  TemporaryRows rows_;
};

}  // namespace

std::unique_ptr<RowReader> spill_decoded_rows(const std::filesystem::path& path, const cv::Mat& image) {
  return std::make_unique<SpilledRows>(path, image);
}

}  // namespace lightstage::io
