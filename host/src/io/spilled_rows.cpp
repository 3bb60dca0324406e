// Rows of a file that decodes only whole, kept in an unlinked temporary file.
#include "io/row_readers.hpp"
#include "lightstage/common/error.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <system_error>

namespace lightstage::io {
namespace {

namespace fs = std::filesystem;

// An unlinked file in `dir`: gone with its descriptor, whatever ends the process.
int open_unlinked_file(const fs::path& dir) {
  int fd = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
  if (fd >= 0 || (errno != EOPNOTSUPP && errno != EISDIR && errno != EINVAL)) return fd;
  // A file system without O_TMPFILE: a named file, unlinked at once.
  std::string name = (dir / "lightstage-rows-XXXXXX").string();
  fd = ::mkostemp(name.data(), O_CLOEXEC);
  if (fd >= 0) ::unlink(name.c_str());
  return fd;
}

class SpilledRows final : public RowReader {
 public:
  SpilledRows(const fs::path& path, const cv::Mat& image)
      : RowReader(path, image.size(), image.type()), row_bytes_(image.cols * image.elemSize()) {
    std::error_code error;
    const fs::path dir = fs::temp_directory_path(error);
    const std::size_t bytes = row_bytes_ * static_cast<std::size_t>(image.rows);
    auto refuse = [&](const char* what) {
      fail(
          "{}: cannot keep its {} MB of decoded rows in a temporary file in {} ({}: {}); set TMPDIR to a "
          "folder with room",
          path.string(), (bytes + (1u << 20) - 1) >> 20, error ? "$TMPDIR" : dir.string(), what,
          std::strerror(errno));
    };
    if (error) {
      errno = error.value();
      refuse("no temporary folder");
    }
    fd_ = open_unlinked_file(dir);
    if (fd_ < 0) refuse("open");
    const cv::Mat rows = image.isContinuous() ? image : image.clone();
    const auto* data = rows.ptr<const char>();
    for (std::size_t done = 0; done < bytes;) {
      const ssize_t n = ::write(fd_, data + done, bytes - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        if (n == 0) errno = ENOSPC;
        refuse("write");
      }
      done += static_cast<std::size_t>(n);
    }
  }
  ~SpilledRows() override { ::close(fd_); }
  bool decoded_whole() const override { return true; }

 private:
  void read_rows(int y0, int rows, cv::Mat& out) override {
    auto* data = out.ptr<char>();
    const std::size_t bytes = row_bytes_ * static_cast<std::size_t>(rows);
    const auto offset = static_cast<off_t>(row_bytes_ * static_cast<std::size_t>(y0));
    for (std::size_t done = 0; done < bytes;) {
      const ssize_t n = ::pread(fd_, data + done, bytes - done, offset + static_cast<off_t>(done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0)
        fail("{}: cannot read its decoded rows {} to {} back from the temporary file: {}", path().string(),
             y0, y0 + rows - 1, n == 0 ? "file shortened" : std::strerror(errno));
      done += static_cast<std::size_t>(n);
    }
  }

  std::size_t row_bytes_;
  int fd_ = -1;
};

}  // namespace

std::unique_ptr<RowReader> spill_decoded_rows(const fs::path& path, const cv::Mat& image) {
  return std::make_unique<SpilledRows>(path, image);
}

}  // namespace lightstage::io
