#pragma once
// The v4l2: camera backend. All of its system calls go through V4l2Syscalls,
// a seam as thin as the calls themselves, so tests can put a fake device
// behind it (there is no /dev/video* in CI). Every call returns what the
// system call returns and sets errno the same way.
//
// URI: v4l2:/dev/videoN (or v4l2:N), with options after '?':
//   exposure_unit_us=U  the length of one V4L2_CID_EXPOSURE step in µs, for
//                       sensors whose exposure control counts lines and whose
//                       node has no V4L2_CID_PIXEL_RATE / V4L2_CID_HBLANK to
//                       work it out from (cameras with V4L2_CID_EXPOSURE_ABSOLUTE
//                       need nothing: its unit is 100 µs)
//   gain_unity=N        the gain control's value that means 1x (default: the
//                       control's default value, or 1 when that is 0)

#include "lightstage/common/camera.hpp"

#include <poll.h>
#include <sys/types.h>

#include <cstddef>
#include <memory>

namespace lightstage::hw {

class V4l2Syscalls {
 public:
  virtual ~V4l2Syscalls() = default;
  virtual int open(const char* path, int flags) = 0;
  virtual int close(int fd) = 0;
  virtual int ioctl(int fd, unsigned long request, void* arg) = 0;
  virtual void* mmap(std::size_t length, int prot, int flags, int fd, off_t offset) = 0;
  virtual int munmap(void* addr, std::size_t length) = 0;
  virtual int poll(pollfd* fds, nfds_t count, int timeout_ms) = 0;
};

// The real system calls.
std::shared_ptr<V4l2Syscalls> system_v4l2_syscalls();

// Opens the device named by `uri` (scheme v4l2) through `sys`. Throws
// InputError for a malformed target or option, CameraError (naming the URI)
// when the device is missing, busy, not a streaming capture device, or fails.
std::unique_ptr<camera::Camera> open_v4l2_camera(const camera::CameraUri& uri,
                                                 std::shared_ptr<V4l2Syscalls> sys = system_v4l2_syscalls());

}  // namespace lightstage::hw
