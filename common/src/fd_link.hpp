#pragma once
// A ByteLink over a connected stream file descriptor (socket, pty, tty),
// waiting with poll(). Shared by the socket and serial links.

#include "lightstage/common/link.hpp"

#include <atomic>
#include <string>

namespace lightstage {

class FdLink : public ByteLink {
 public:
  // Takes ownership of `fd`.
  FdLink(int fd, std::string description);
  ~FdLink() override;
  FdLink(const FdLink&) = delete;
  FdLink& operator=(const FdLink&) = delete;

  std::size_t read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) override;
  void write(std::span<const std::uint8_t> bytes) override;
  void shutdown() override;
  std::string describe() const override { return description_; }

 protected:
  int fd() const { return fd_; }

 private:
  int fd_;
  int wake_[2] = {-1, -1};  // a pipe that shutdown() writes to, waking a poll() in read()
  std::atomic<bool> closed_{false};
  std::string description_;
};

}  // namespace lightstage
