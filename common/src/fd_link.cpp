#include "fd_link.hpp"

#include <fmt/format.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fcntl.h>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>

namespace lightstage {

FdLink::FdLink(int fd, std::string description) : fd_(fd), description_(std::move(description)) {
  if (pipe2(wake_, O_CLOEXEC | O_NONBLOCK) != 0) {
    ::close(fd_);
    throw LinkClosed(fmt::format("{}: pipe: {}", description_, std::strerror(errno)));
  }
}

FdLink::~FdLink() {
  ::close(fd_);
  ::close(wake_[0]);
  ::close(wake_[1]);
}

std::size_t FdLink::read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) {
  if (closed_) throw LinkClosed(fmt::format("{}: link closed", description_));
  pollfd fds[2] = {{fd_, POLLIN, 0}, {wake_[0], POLLIN, 0}};
  const int ready = ::poll(fds, 2, static_cast<int>(std::max<std::int64_t>(0, timeout.count())));
  if (ready < 0) {
    if (errno == EINTR) return 0;
    throw LinkClosed(fmt::format("{}: poll: {}", description_, std::strerror(errno)));
  }
  if (closed_ || (fds[1].revents & POLLIN)) throw LinkClosed(fmt::format("{}: link closed", description_));
  if (ready == 0) return 0;
  const ssize_t n = ::read(fd_, buffer.data(), buffer.size());
  if (n > 0) return static_cast<std::size_t>(n);
  if (n < 0 && (errno == EINTR || errno == EAGAIN)) return 0;
  throw LinkClosed(n == 0 ? fmt::format("{}: closed by the peer", description_)
                          : fmt::format("{}: read: {}", description_, std::strerror(errno)));
}

void FdLink::write(std::span<const std::uint8_t> bytes) {
  // A peer that keeps the link open but stops reading must not block the
  // writer for ever (the controller writes step events from its sequencer).
  constexpr auto kStall = std::chrono::seconds(10);
  std::size_t done = 0;
  auto give_up_at = std::chrono::steady_clock::now() + kStall;
  while (done < bytes.size()) {
    if (closed_) throw LinkClosed(fmt::format("{}: link closed", description_));
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(give_up_at - std::chrono::steady_clock::now());
    pollfd out{fd_, POLLOUT, 0};
    const int ready = ::poll(&out, 1, static_cast<int>(std::max<std::int64_t>(0, left.count())));
    if (ready == 0) {
      throw LinkClosed(fmt::format("{}: the peer has read nothing for {} s", description_, kStall.count()));
    }
    // MSG_NOSIGNAL where the fd is a socket: a dead peer must not raise SIGPIPE.
    ssize_t n = ::send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n < 0 && errno == ENOTSOCK) n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      throw LinkClosed(fmt::format("{}: write: {}", description_, std::strerror(errno)));
    }
    done += static_cast<std::size_t>(n);
    give_up_at = std::chrono::steady_clock::now() + kStall;
  }
}

void FdLink::shutdown() {
  if (closed_.exchange(true)) return;
  const std::uint8_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(wake_[1], &one, 1);
  ::shutdown(fd_, SHUT_RDWR);  // fails harmlessly on a tty
}

}  // namespace lightstage
