#include "lightstage/host/io/temporary_rows.hpp"

#include "lightstage/common/error.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
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

}  // namespace

TemporaryRows::TemporaryRows(std::string what, int width, int type, int rows)
    : what_(std::move(what)),
      width_(width),
      type_(type),
      row_bytes_(static_cast<std::size_t>(width) * CV_ELEM_SIZE(type)),
      expected_rows_(rows) {
  std::error_code error;
  const fs::path dir = fs::temp_directory_path(error);
  if (error) {
    errno = error.value();
    refuse("no temporary folder");
  }
  fd_ = open_unlinked_file(dir);
  if (fd_ < 0) refuse("open");
}

TemporaryRows::~TemporaryRows() {
  if (fd_ >= 0) ::close(fd_);
}

void TemporaryRows::refuse(const char* step) const {
  const int cause = errno;  // before the calls below can change it
  std::error_code error;
  const fs::path dir = fs::temp_directory_path(error);
  const std::size_t bytes = row_bytes_ * static_cast<std::size_t>(std::max(expected_rows_, rows_));
  fail(
      "{}: cannot keep its {} MB of decoded rows in a temporary file in {} ({}: {}); set TMPDIR to a folder "
      "with room",
      what_, (bytes + (1u << 20) - 1) >> 20, error ? "$TMPDIR" : dir.string(), step, std::strerror(cause));
}

void TemporaryRows::append(const cv::Mat& rows) {
  CV_Assert(rows.cols == width_ && rows.type() == type_);
  const cv::Mat data = rows.isContinuous() ? rows : rows.clone();
  const auto* bytes = data.ptr<const char>();
  const std::size_t total = row_bytes_ * static_cast<std::size_t>(rows.rows);
  const auto offset = static_cast<off_t>(row_bytes_ * static_cast<std::size_t>(rows_));
  for (std::size_t done = 0; done < total;) {
    const ssize_t n = ::pwrite(fd_, bytes + done, total - done, offset + static_cast<off_t>(done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = ENOSPC;
      refuse("write");
    }
    done += static_cast<std::size_t>(n);
  }
  rows_ += rows.rows;
}

void TemporaryRows::read(int y0, int count, cv::Mat& out) const {
  CV_Assert(y0 >= 0 && count >= 0 && y0 + count <= rows_);
  out.create(count, width_, type_);
  auto* data = out.ptr<char>();
  const std::size_t bytes = row_bytes_ * static_cast<std::size_t>(count);
  const auto offset = static_cast<off_t>(row_bytes_ * static_cast<std::size_t>(y0));
  for (std::size_t done = 0; done < bytes;) {
    const ssize_t n = ::pread(fd_, data + done, bytes - done, offset + static_cast<off_t>(done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      fail("{}: cannot read its decoded rows {} to {} back from the temporary file: {}", what_, y0,
           y0 + count - 1, n == 0 ? "file shortened" : std::strerror(errno));
    done += static_cast<std::size_t>(n);
  }
}

}  // namespace lightstage::io
