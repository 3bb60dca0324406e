#include "util/atomic_file.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/write_fault.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <system_error>
#include <utility>

namespace lightstage::util {
namespace {

std::mutex fault_mutex;
io::WriteFault installed_fault;

int injected_errno(const std::filesystem::path& target) {
  const std::lock_guard lock(fault_mutex);
  return installed_fault ? installed_fault(target) : 0;
}

[[noreturn]] void fail_write(const std::filesystem::path& target, int error) {
  if (error == ENOSPC || error == EDQUOT) {
    // Not the path's fault: the capture can go on (--resume) once there is room.
    throw Error(fmt::format("{}: cannot write: no space left on the device ({}); free some space",
                            target.string(), error == ENOSPC ? "ENOSPC" : "EDQUOT"));
  }
  fail("{}: cannot write: {}", target.string(), std::strerror(error));
}

}  // namespace

void commit_temporary(const std::filesystem::path& temporary, const std::filesystem::path& target) {
  std::error_code error;
  std::filesystem::rename(temporary, target, error);
  if (error) {
    std::filesystem::remove(temporary, error);
    fail("{}: cannot write: {}", target.string(), error.message());
  }
}

std::filesystem::path write_temporary(const std::filesystem::path& target, std::string_view bytes) {
  const std::filesystem::path temporary = temporary_sibling(target);
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) {
    const int error = errno;
    if (error == ENOSPC || error == EDQUOT) fail_write(target, error);
    fail("{}: cannot write: cannot create a file in this folder ({})", target.string(), std::strerror(error));
  }
  int error = injected_errno(target);
  for (std::size_t done = 0; error == 0 && done < bytes.size();) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno != EINTR) error = errno;
      continue;
    }
    done += static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0 && error == 0) error = errno;
  if (error != 0) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    fail_write(target, error);
  }
  return temporary;
}

void write_text_atomic(const std::filesystem::path& path, std::string_view text) {
  commit_temporary(write_temporary(path, text), path);
}

TemporaryFile::TemporaryFile(std::filesystem::path target)
    : target_(std::move(target)), temporary_(temporary_sibling(target_)) {
  fd_ = ::open(temporary_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd_ < 0) {
    const int error = errno;
    if (error == ENOSPC || error == EDQUOT) fail_write(target_, error);
    fail("{}: cannot write: cannot create a file in this folder ({})", target_.string(),
         std::strerror(error));
  }
  if (const int error = injected_errno(target_); error != 0) {
    close_and_remove();
    fail_write(target_, error);
  }
}

TemporaryFile::~TemporaryFile() { close_and_remove(); }

void TemporaryFile::close_and_remove() {
  if (fd_ < 0) return;
  ::close(fd_);
  fd_ = -1;
  std::error_code ignored;
  std::filesystem::remove(temporary_, ignored);
}

void TemporaryFile::write_at(std::uint64_t offset, std::string_view bytes) {
  if (failed_ != 0) fail_write(target_, failed_);
  if (fd_ < 0) fail("{}: cannot write: the file is already closed", target_.string());
  for (std::size_t done = 0; done < bytes.size();) {
    const ssize_t n =
        ::pwrite(fd_, bytes.data() + done, bytes.size() - done, static_cast<off_t>(offset + done));
    if (n < 0) {
      if (errno == EINTR) continue;
      failed_ = errno;
      close_and_remove();
      fail_write(target_, failed_);
    }
    done += static_cast<std::size_t>(n);
  }
  end_ = std::max<std::uint64_t>(end_, offset + bytes.size());
}

void TemporaryFile::commit() {
  if (failed_ != 0) fail_write(target_, failed_);  // a write failed where its error could not be seen
  if (fd_ < 0) fail("{}: cannot write: the file is already closed", target_.string());
  const int closed = ::close(fd_);
  const int error = closed != 0 ? errno : 0;
  fd_ = -1;
  if (error != 0) {
    std::error_code ignored;
    std::filesystem::remove(temporary_, ignored);
    fail_write(target_, error);
  }
  commit_temporary(temporary_, target_);
}

}  // namespace lightstage::util

namespace lightstage::io {

ScopedWriteFault::ScopedWriteFault(WriteFault fault) {
  const std::lock_guard lock(util::fault_mutex);
  util::installed_fault = std::move(fault);
}

ScopedWriteFault::~ScopedWriteFault() {
  const std::lock_guard lock(util::fault_mutex);
  util::installed_fault = nullptr;
}

}  // namespace lightstage::io
