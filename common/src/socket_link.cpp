#include "lightstage/common/socket_link.hpp"

#include "fd_link.hpp"

#include <fmt/format.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <thread>

namespace lightstage {
namespace {

struct SocketAddress {
  enum class Kind { kTcp, kUnix } kind;
  std::string host;  // tcp
  std::string port;  // tcp
  std::string path;  // unix
};

SocketAddress parse_uri(const std::string& uri) {
  if (uri.starts_with("unix:")) {
    SocketAddress a{SocketAddress::Kind::kUnix, {}, {}, uri.substr(5)};
    if (a.path.empty()) fail("link '{}': a unix: URI needs a socket path", uri);
    if (a.path.size() >= sizeof(sockaddr_un::sun_path)) {
      fail("link '{}': the socket path is {} bytes, longer than the {} a Unix socket allows", uri,
           a.path.size(), sizeof(sockaddr_un::sun_path) - 1);
    }
    return a;
  }
  if (uri.starts_with("tcp:")) {
    const std::string rest = uri.substr(4);
    const auto colon = rest.rfind(':');
    if (colon == std::string::npos) fail("link '{}': expected tcp:HOST:PORT", uri);
    SocketAddress a{SocketAddress::Kind::kTcp, rest.substr(0, colon), rest.substr(colon + 1), {}};
    if (a.host.starts_with('[') && a.host.ends_with(']')) a.host = a.host.substr(1, a.host.size() - 2);
    int port = -1;
    const auto [end, ec] = std::from_chars(a.port.data(), a.port.data() + a.port.size(), port);
    if (ec != std::errc() || end != a.port.data() + a.port.size() || port < 0 || port > 65535) {
      fail("link '{}': port '{}' is not a number in 0..65535", uri, a.port);
    }
    if (a.host.empty()) a.host = "0.0.0.0";
    return a;
  }
  fail("link '{}': not a socket URI (expected tcp:HOST:PORT or unix:PATH)", uri);
}

sockaddr_un unix_address(const std::string& path) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  return addr;
}

const sockaddr* as_sockaddr(const sockaddr_un& a) { return reinterpret_cast<const sockaddr*>(&a); }

std::string errno_text() { return std::strerror(errno); }

struct AddrInfoDeleter {
  void operator()(addrinfo* p) const { freeaddrinfo(p); }
};
using AddrInfoPtr = std::unique_ptr<addrinfo, AddrInfoDeleter>;

AddrInfoPtr resolve(const std::string& uri, const SocketAddress& a, bool passive) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = passive ? AI_PASSIVE : 0;
  addrinfo* result = nullptr;
  const int rc = getaddrinfo(a.host.c_str(), a.port.c_str(), &hints, &result);
  if (rc != 0)
    throw LinkClosed(fmt::format("link '{}': cannot resolve '{}': {}", uri, a.host, gai_strerror(rc)));
  return AddrInfoPtr(result);
}

std::string peer_name(int fd) {
  sockaddr_storage peer{};
  socklen_t len = sizeof(peer);
  if (getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &len) != 0) return "?";
  char host[NI_MAXHOST], port[NI_MAXSERV];
  if (getnameinfo(reinterpret_cast<sockaddr*>(&peer), len, host, sizeof(host), port, sizeof(port),
                  NI_NUMERICHOST | NI_NUMERICSERV) != 0) {
    return "?";
  }
  return fmt::format("{}:{}", host, port);
}

// One connection attempt; returns the fd or -1 with errno set.
int try_connect(const std::string& uri, const SocketAddress& a) {
  if (a.kind == SocketAddress::Kind::kUnix) {
    const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) return -1;
    const sockaddr_un addr = unix_address(a.path);
    if (::connect(fd, as_sockaddr(addr), sizeof(addr)) == 0) return fd;
    const int saved = errno;
    ::close(fd);
    errno = saved;
    return -1;
  }
  const AddrInfoPtr list = resolve(uri, a, false);
  int saved = ECONNREFUSED;
  for (addrinfo* ai = list.get(); ai != nullptr; ai = ai->ai_next) {
    const int fd = ::socket(ai->ai_family, ai->ai_socktype | SOCK_CLOEXEC, ai->ai_protocol);
    if (fd < 0) continue;
    if (::connect(fd, ai->ai_addr, ai->ai_addrlen) == 0) {
      const int one = 1;
      setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));  // small frames go out at once
      return fd;
    }
    saved = errno;
    ::close(fd);
  }
  errno = saved;
  return -1;
}

class SocketListener final : public LinkListener {
 public:
  SocketListener(int fd, std::string uri, std::string unix_path)
      : fd_(fd), uri_(std::move(uri)), unix_path_(std::move(unix_path)) {}
  ~SocketListener() override {
    ::close(fd_);
    if (!unix_path_.empty()) ::unlink(unix_path_.c_str());
  }
  SocketListener(const SocketListener&) = delete;
  SocketListener& operator=(const SocketListener&) = delete;

  std::unique_ptr<ByteLink> accept(std::chrono::milliseconds timeout) override {
    pollfd p{fd_, POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(std::max<std::int64_t>(0, timeout.count())));
    if (ready <= 0) return nullptr;
    const int fd = ::accept4(fd_, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EINTR || errno == EAGAIN || errno == ECONNABORTED) return nullptr;
      throw LinkClosed(fmt::format("{}: accept: {}", uri_, errno_text()));
    }
    std::string description = uri_;
    if (unix_path_.empty()) {
      const int one = 1;
      setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
      description += fmt::format(" (peer {})", peer_name(fd));
    }
    return std::make_unique<FdLink>(fd, description);
  }

  std::string describe() const override { return uri_; }

 private:
  int fd_;
  std::string uri_;
  std::string unix_path_;
};

std::unique_ptr<LinkListener> listen_unix(const std::string& uri, const SocketAddress& a) {
  // A socket file nobody listens on is left over from a crash: replace it. A live one is someone else's.
  if (::access(a.path.c_str(), F_OK) == 0) {
    const int probe = try_connect(uri, a);
    if (probe >= 0) {
      ::close(probe);
      throw LinkClosed(fmt::format("link '{}': another process is already listening there", uri));
    }
    ::unlink(a.path.c_str());
  }
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw LinkClosed(fmt::format("link '{}': socket: {}", uri, errno_text()));
  const sockaddr_un addr = unix_address(a.path);
  if (::bind(fd, as_sockaddr(addr), sizeof(addr)) != 0 || ::listen(fd, 8) != 0) {
    const std::string why = errno_text();
    ::close(fd);
    throw LinkClosed(fmt::format("link '{}': cannot listen: {}", uri, why));
  }
  return std::make_unique<SocketListener>(fd, uri, a.path);
}

std::unique_ptr<LinkListener> listen_tcp(const std::string& uri, const SocketAddress& a) {
  const AddrInfoPtr list = resolve(uri, a, true);
  std::string why = "no address";
  for (addrinfo* ai = list.get(); ai != nullptr; ai = ai->ai_next) {
    const int fd = ::socket(ai->ai_family, ai->ai_socktype | SOCK_CLOEXEC, ai->ai_protocol);
    if (fd < 0) continue;
    const int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
    if (::bind(fd, ai->ai_addr, ai->ai_addrlen) == 0 && ::listen(fd, 8) == 0) {
      sockaddr_storage bound{};
      socklen_t len = sizeof(bound);
      getsockname(fd, reinterpret_cast<sockaddr*>(&bound), &len);
      char host[NI_MAXHOST], port[NI_MAXSERV];
      getnameinfo(reinterpret_cast<sockaddr*>(&bound), len, host, sizeof(host), port, sizeof(port),
                  NI_NUMERICHOST | NI_NUMERICSERV);
      const std::string h = std::strchr(host, ':') ? fmt::format("[{}]", host) : std::string(host);
      return std::make_unique<SocketListener>(fd, fmt::format("tcp:{}:{}", h, port), std::string());
    }
    why = errno_text();
    ::close(fd);
  }
  throw LinkClosed(fmt::format("link '{}': cannot listen: {}", uri, why));
}

}  // namespace

std::unique_ptr<ByteLink> connect_socket_link(const std::string& uri, std::chrono::milliseconds timeout) {
  const SocketAddress a = parse_uri(uri);
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const int fd = try_connect(uri, a);
    if (fd >= 0) {
      const std::string peer =
          a.kind == SocketAddress::Kind::kTcp ? fmt::format(" (peer {})", peer_name(fd)) : "";
      return std::make_unique<FdLink>(fd, uri + peer);
    }
    const bool retry = errno == ENOENT || errno == ECONNREFUSED || errno == EAGAIN;
    if (!retry || std::chrono::steady_clock::now() >= deadline) {
      throw LinkClosed(fmt::format("link '{}': cannot connect: {}", uri, errno_text()));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

std::unique_ptr<LinkListener> listen_socket_link(const std::string& uri) {
  const SocketAddress a = parse_uri(uri);
  return a.kind == SocketAddress::Kind::kUnix ? listen_unix(uri, a) : listen_tcp(uri, a);
}

std::string bound_uri(const LinkListener& listener) { return listener.describe(); }

std::pair<std::unique_ptr<ByteLink>, std::unique_ptr<ByteLink>> socket_link_pair() {
  int fds[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) {
    throw LinkClosed(fmt::format("socketpair: {}", errno_text()));
  }
  return {std::make_unique<FdLink>(fds[0], "pair:a"), std::make_unique<FdLink>(fds[1], "pair:b")};
}

}  // namespace lightstage
