#include "lightstage/common/serial_link.hpp"

#include "fd_link.hpp"
#include "lightstage/common/error.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <mutex>
#include <thread>
#include <utility>

namespace lightstage {
namespace {

struct BaudRate {
  std::uint32_t rate;
  speed_t code;
};

// What termios can set on Linux (B* constants); cfsetspeed takes only these.
constexpr BaudRate kBaudRates[] = {
    {1200, B1200},       {2400, B2400},       {4800, B4800},       {9600, B9600},       {19200, B19200},
    {38400, B38400},     {57600, B57600},     {115200, B115200},   {230400, B230400},   {460800, B460800},
    {500000, B500000},   {576000, B576000},   {921600, B921600},   {1000000, B1000000}, {1152000, B1152000},
    {1500000, B1500000}, {2000000, B2000000}, {2500000, B2500000}, {3000000, B3000000}, {3500000, B3500000},
    {4000000, B4000000},
};

speed_t baud_code(std::uint32_t rate) {
  for (const auto& baud : kBaudRates) {
    if (baud.rate == rate) return baud.code;
  }
  return B0;
}

std::string supported_rates() {
  std::string list;
  for (const auto& baud : kBaudRates) list += (list.empty() ? "" : ", ") + std::to_string(baud.rate);
  return list;
}

std::string describe(const SerialOptions& options) {
  return fmt::format("serial:{} ({} baud{})", options.device, options.baud,
                     options.hardware_flow_control ? ", RTS/CTS" : "");
}

// Raw 8N1. VMIN=1/VTIME=0: the descriptor stays O_NONBLOCK and FdLink waits
// with poll(), so termios never times reads itself; but with VMIN=0 a read
// with no data would return 0, which is indistinguishable from a hang-up.
void configure_raw(int fd, const SerialOptions& options, const std::string& what) {
  termios tio{};
  if (::tcgetattr(fd, &tio) != 0) {
    throw InputError(fmt::format("{}: not a terminal ({})", what, std::strerror(errno)));
  }
  ::cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;  // ignore modem lines for opening; enable the receiver
  tio.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | CRTSCTS);
  if (options.hardware_flow_control) tio.c_cflag |= CRTSCTS;
  tio.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);  // XON/XOFF bytes are data here
  tio.c_cc[VMIN] = 1;
  tio.c_cc[VTIME] = 0;
  const speed_t speed = baud_code(options.baud);
  if (::cfsetispeed(&tio, speed) != 0 || ::cfsetospeed(&tio, speed) != 0 ||
      ::tcsetattr(fd, TCSANOW, &tio) != 0) {
    throw LinkClosed(fmt::format("{}: cannot configure the line: {}", what, std::strerror(errno)));
  }
  // tcsetattr succeeds when any of the changes took: check the ones that matter.
  termios applied{};
  if (::tcgetattr(fd, &applied) != 0 || (applied.c_lflag & (ICANON | ECHO | ISIG)) != 0 ||
      (applied.c_cflag & CSIZE) != CS8 || (applied.c_oflag & OPOST) != 0 ||
      ((applied.c_cflag & CRTSCTS) != 0) != options.hardware_flow_control) {
    throw LinkClosed(fmt::format("{}: the driver refused raw mode", what));
  }
  ::tcflush(fd, TCIOFLUSH);  // bytes left over from before we opened are not ours
}

// Errors that mean "not there yet" (a gadget not bound, a board not plugged,
// a pty whose other end is gone): a listener keeps waiting on these.
bool device_absent(int error) { return error == ENOENT || error == ENXIO || error == ENODEV || error == EIO; }

// Opens and configures the device; returns -1 with errno set for open() failures.
int open_device(const SerialOptions& options, const std::string& what) {
  const int fd = ::open(options.device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return -1;
  try {
    if (!::isatty(fd)) throw InputError(fmt::format("{}: {} is not a terminal", what, options.device));
    // Two processes talking on one line would split each other's frames. TIOCEXCL
    // stops other openers (except root); flock also catches a second opener that is root.
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      throw LinkClosed(fmt::format("{}: {} is in use by another program", what, options.device));
    }
    ::ioctl(fd, TIOCEXCL);
    configure_raw(fd, options, what);
  } catch (...) {
    ::close(fd);
    throw;
  }
  return fd;
}

// Cleared when the link is gone. A base class placed before FdLink, so it is
// destroyed after FdLink has closed the line: the listener never reopens a
// line that is still locked.
struct InUseFlag {
  std::shared_ptr<std::atomic<bool>> flag;
  ~InUseFlag() {
    if (flag) flag->store(false);
  }
};

// The link handed out by open_serial_link and the listener: FdLink, but a
// write the other end takes nothing of for kWriteTimeout fails. A tty has no
// connection to break: with no program reading on the host, a CDC-ACM gadget's
// buffer fills and would block the controller's writer for good.
class SerialLink final : private InUseFlag, public FdLink {
 public:
  static constexpr auto kWriteTimeout = std::chrono::seconds(5);

  SerialLink(int fd, std::string description, std::shared_ptr<std::atomic<bool>> in_use)
      : InUseFlag{std::move(in_use)}, FdLink(fd, std::move(description)) {}

  void write(std::span<const std::uint8_t> bytes) override {
    const std::lock_guard lock(write_mutex_);
    auto last_progress = std::chrono::steady_clock::now();
    std::size_t done = 0;
    while (done < bytes.size()) {
      if (stopped_) throw LinkClosed(fmt::format("{}: link closed", describe()));
      const ssize_t n = ::write(fd(), bytes.data() + done, bytes.size() - done);
      if (n > 0) {
        done += static_cast<std::size_t>(n);
        last_progress = std::chrono::steady_clock::now();
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && errno != EAGAIN) {
        throw LinkClosed(fmt::format("{}: write: {}", describe(), std::strerror(errno)));  // EIO: hung up
      }
      if (std::chrono::steady_clock::now() - last_progress > kWriteTimeout) {
        throw LinkClosed(fmt::format("{}: the other end took no data for {} s (is a program reading it?)",
                                     describe(), kWriteTimeout.count()));
      }
      pollfd out{fd(), POLLOUT, 0};
      ::poll(&out, 1, 50);
    }
  }

  void shutdown() override {
    stopped_ = true;
    FdLink::shutdown();
  }

 private:
  std::mutex write_mutex_;
  std::atomic<bool> stopped_{false};
};

class SerialListener final : public LinkListener {
 public:
  explicit SerialListener(SerialOptions options) : options_(std::move(options)) {}

  std::unique_ptr<ByteLink> accept(std::chrono::milliseconds timeout) override {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    const std::string what = describe();
    for (;;) {
      if (!in_use_->load()) {
        const int fd = open_device(options_, what);
        if (fd >= 0) {
          in_use_->store(true);
          return std::make_unique<SerialLink>(fd, what, in_use_);
        }
        if (!device_absent(errno)) {
          throw LinkClosed(
              fmt::format("{}: cannot open {}: {}", what, options_.device, std::strerror(errno)));
        }
      }
      const auto now = std::chrono::steady_clock::now();
      if (now >= deadline) return nullptr;
      std::this_thread::sleep_for(
          std::min<std::chrono::steady_clock::duration>(deadline - now, std::chrono::milliseconds(50)));
    }
  }

  std::string describe() const override { return lightstage::describe(options_); }

 private:
  SerialOptions options_;
  std::shared_ptr<std::atomic<bool>> in_use_ = std::make_shared<std::atomic<bool>>(false);
};

}  // namespace

const std::vector<std::uint32_t>& serial_baud_rates() {
  static const std::vector<std::uint32_t> rates = [] {
    std::vector<std::uint32_t> out;
    for (const auto& baud : kBaudRates) out.push_back(baud.rate);
    return out;
  }();
  return rates;
}

SerialOptions parse_serial_uri(const std::string& uri) {
  const std::string prefix = std::string(kSerialScheme) + ":";
  if (uri.rfind(prefix, 0) != 0) fail("'{}' is not a serial: URI", uri);
  std::vector<std::string> parts;
  std::size_t begin = prefix.size();
  for (;;) {
    const std::size_t comma = uri.find(',', begin);
    parts.push_back(uri.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin));
    if (comma == std::string::npos) break;
    begin = comma + 1;
  }
  SerialOptions options;
  options.device = parts.front();
  if (options.device.empty()) fail("'{}': no device (expected serial:/dev/ttyACM0[,BAUD][,rtscts])", uri);
  bool baud_given = false;
  for (std::size_t i = 1; i < parts.size(); ++i) {
    const std::string& part = parts[i];
    if (part == "rtscts") {
      options.hardware_flow_control = true;
      continue;
    }
    std::uint32_t rate = 0;
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), rate);
    if (part.empty() || ec != std::errc() || end != part.data() + part.size()) {
      fail("'{}': unknown option '{}' (expected a baud rate or 'rtscts')", uri, part);
    }
    if (baud_given) fail("'{}': baud rate given twice", uri);
    if (baud_code(rate) == B0)
      fail("'{}': unsupported baud rate {} (supported: {})", uri, rate, supported_rates());
    options.baud = rate;
    baud_given = true;
  }
  return options;
}

std::unique_ptr<ByteLink> open_serial_link(const std::string& uri) {
  const SerialOptions options = parse_serial_uri(uri);
  const std::string what = describe(options);
  const int fd = open_device(options, what);
  if (fd < 0)
    throw LinkClosed(fmt::format("{}: cannot open {}: {}", what, options.device, std::strerror(errno)));
  return std::make_unique<SerialLink>(fd, what, nullptr);
}

std::unique_ptr<LinkListener> listen_serial_link(const std::string& uri) {
  return std::make_unique<SerialListener>(parse_serial_uri(uri));
}

}  // namespace lightstage
