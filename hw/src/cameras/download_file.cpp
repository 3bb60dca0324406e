#include "download_file.hpp"

#include "lightstage/common/camera.hpp"
#include "lightstage/common/temporary_path.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace lightstage::hw {

using camera::CameraError;

void check_download_dir(const std::filesystem::path& dir, const std::string& uri) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    throw CameraError(
        fmt::format("{}: the download folder {} does not exist (or is not a folder)", uri, dir.string()));
  }
  if (::access(dir.c_str(), W_OK | X_OK) != 0) {
    throw CameraError(fmt::format("{}: cannot write into the download folder {}: {}", uri, dir.string(),
                                  std::strerror(errno)));
  }
}

std::filesystem::path write_new_file(const std::filesystem::path& dir, std::string_view name,
                                     const std::string& uri, const std::function<void(int fd)>& write) {
  std::string base = std::filesystem::path(std::string(name)).filename().string();
  if (base.empty() || base == "." || base == "..") base = "shot";
  const std::filesystem::path first = dir / base;
  const std::filesystem::path temporary = temporary_sibling(first);
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    throw CameraError(fmt::format("{}: cannot create {} in the download folder: {}", uri, temporary.string(),
                                  std::strerror(errno)));
  }
  try {
    write(fd);
  } catch (...) {
    ::close(fd);
    ::unlink(temporary.c_str());
    throw;
  }
  if (::close(fd) != 0) {  // a late write error (full disk on a network file system) shows here
    const int err = errno;
    ::unlink(temporary.c_str());
    throw CameraError(fmt::format("{}: writing {} failed: {}", uri, temporary.string(), std::strerror(err)));
  }
  const std::string stem = first.stem().string();
  const std::string extension = first.extension().string();
  constexpr int kMaxSuffix = 100000;
  for (int n = 0; n < kMaxSuffix; ++n) {
    const std::filesystem::path target = n == 0 ? first : dir / fmt::format("{}-{}{}", stem, n, extension);
    if (::renameat2(AT_FDCWD, temporary.c_str(), AT_FDCWD, target.c_str(), RENAME_NOREPLACE) == 0)
      return target;
    int err = errno;
    if (err == EINVAL || err == ENOSYS) {
      // A file system without RENAME_NOREPLACE (vfat, some network ones):
      // look first; only a writer picking the same name at the same moment
      // could still lose its file.
      std::error_code ec;
      if (std::filesystem::exists(target, ec)) continue;
      if (::rename(temporary.c_str(), target.c_str()) == 0) return target;
      err = errno;
    }
    if (err == EEXIST) continue;
    ::unlink(temporary.c_str());
    throw CameraError(fmt::format("{}: cannot rename {} to {}: {}", uri, temporary.string(), target.string(),
                                  std::strerror(err)));
  }
  ::unlink(temporary.c_str());
  throw CameraError(
      fmt::format("{}: {} and {} numbered names beside it are all taken", uri, first.string(), kMaxSuffix));
}

}  // namespace lightstage::hw
