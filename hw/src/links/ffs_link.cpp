// ffs: links — the controller's side of a USB link, through Linux FunctionFS.
//
// FunctionFS endpoint files do not support poll(), and a blocking read() on
// them can only be ended by the host or a signal. So data moves through Linux
// native AIO (io_submit; completions signalled on an eventfd, which poll()
// waits on together with a wake-up pipe): reads get timeouts, and shutdown()
// or a stuck write can cancel the request in flight.
#include "lightstage/hw/ffs_link.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/hw/ffs_descriptors.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <linux/aio_abi.h>
#include <linux/usb/ch9.h>
#include <linux/usb/functionfs.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <utility>
#include <vector>

namespace lightstage::hw {
namespace {

using namespace std::chrono_literals;

constexpr std::size_t kBufferSize = 16 * 1024;  // a multiple of every bulk max packet size
constexpr auto kWriteTimeout = 5s;

std::string errno_text(int error) { return std::strerror(error); }

// glibc has no wrappers for the native AIO system calls.
long io_setup(unsigned events, aio_context_t* context) { return ::syscall(SYS_io_setup, events, context); }
long io_destroy(aio_context_t context) { return ::syscall(SYS_io_destroy, context); }
long io_submit(aio_context_t context, long count, iocb** requests) {
  return ::syscall(SYS_io_submit, context, count, requests);
}
long io_getevents(aio_context_t context, long min, long max, io_event* events, timespec* timeout) {
  return ::syscall(SYS_io_getevents, context, min, max, events, timeout);
}
long io_cancel(aio_context_t context, iocb* request, io_event* result) {
  return ::syscall(SYS_io_cancel, context, request, result);
}

class Fd {
 public:
  Fd() = default;
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  Fd(Fd&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  Fd& operator=(Fd&& other) noexcept {
    if (this != &other) {
      if (fd_ >= 0) ::close(fd_);
      fd_ = std::exchange(other.fd_, -1);
    }
    return *this;
  }
  int get() const { return fd_; }

 private:
  int fd_ = -1;
};

// One request at a time on one endpoint file, with its own AIO context and eventfd.
class AioRequest {
 public:
  enum class Wait { kDone, kTimeout, kWoken };

  AioRequest(int fd, std::string what) : fd_(fd), buffer_(kBufferSize), what_(std::move(what)) {
    if (io_setup(1, &context_) != 0)
      throw LinkClosed(fmt::format("{}: io_setup: {}", what_, errno_text(errno)));
    event_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (event_fd_ < 0) {
      io_destroy(context_);
      throw LinkClosed(fmt::format("{}: eventfd: {}", what_, errno_text(errno)));
    }
  }
  ~AioRequest() {
    cancel();
    io_destroy(context_);  // waits for anything still in flight, so buffer_ outlives it
    ::close(event_fd_);
  }
  AioRequest(const AioRequest&) = delete;
  AioRequest& operator=(const AioRequest&) = delete;

  bool in_flight() const { return in_flight_; }
  long result() const { return result_; }
  const std::uint8_t* data() const { return buffer_.data(); }
  std::size_t capacity() const { return buffer_.size(); }

  void submit_read() { submit(IOCB_CMD_PREAD, buffer_.size()); }
  void submit_write(std::span<const std::uint8_t> bytes) {
    std::copy(bytes.begin(), bytes.end(), buffer_.begin());
    submit(IOCB_CMD_PWRITE, bytes.size());
  }

  // Waits for the request in flight to complete, at most `timeout`, or until `wake_fd` is readable.
  Wait wait(std::chrono::milliseconds timeout, int wake_fd) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      if (reap()) return Wait::kDone;
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      pollfd fds[2] = {{event_fd_, POLLIN, 0}, {wake_fd, POLLIN, 0}};
      const int ready = ::poll(fds, 2, static_cast<int>(std::max<std::int64_t>(0, left.count())));
      if (ready < 0 && errno != EINTR)
        throw LinkClosed(fmt::format("{}: poll: {}", what_, errno_text(errno)));
      if (fds[1].revents & POLLIN) return Wait::kWoken;
      if (fds[0].revents & POLLIN) {
        std::uint64_t count = 0;
        [[maybe_unused]] const ssize_t n = ::read(event_fd_, &count, sizeof count);
        continue;
      }
      if (ready == 0 && std::chrono::steady_clock::now() >= deadline)
        return reap() ? Wait::kDone : Wait::kTimeout;
    }
  }

  // Cancels the request in flight (FunctionFS dequeues it from the controller)
  // and waits briefly for its completion.
  void cancel() {
    if (!in_flight_) return;
    io_event event{};
    if (io_cancel(context_, &request_, &event) == 0) {
      in_flight_ = false;
      return;
    }
    timespec patience{1, 0};
    if (io_getevents(context_, 1, 1, &event, &patience) == 1) in_flight_ = false;
  }

 private:
  void submit(std::uint16_t opcode, std::size_t length) {
    request_ = iocb{};
    request_.aio_fildes = static_cast<std::uint32_t>(fd_);
    request_.aio_lio_opcode = opcode;
    request_.aio_buf = reinterpret_cast<std::uint64_t>(buffer_.data());
    request_.aio_nbytes = length;
    request_.aio_offset = 0;
    request_.aio_flags = IOCB_FLAG_RESFD;
    request_.aio_resfd = static_cast<std::uint32_t>(event_fd_);
    iocb* requests[1] = {&request_};
    if (io_submit(context_, 1, requests) != 1) {
      throw LinkClosed(fmt::format("{}: io_submit: {}", what_, errno_text(errno)));
    }
    in_flight_ = true;
  }

  // Collects a completion if there is one.
  bool reap() {
    if (!in_flight_) return false;
    io_event event{};
    timespec now{0, 0};
    if (io_getevents(context_, 0, 1, &event, &now) != 1) return false;
    in_flight_ = false;
    result_ = static_cast<long>(event.res);
    return true;
  }

  int fd_;
  aio_context_t context_ = 0;
  int event_fd_ = -1;
  iocb request_{};
  bool in_flight_ = false;
  long result_ = 0;
  std::vector<std::uint8_t> buffer_;
  std::string what_;
};

// What the listener set up and the links use: ep0 and the two endpoint files.
struct FfsFunction {
  std::string uri;
  std::string mount;
  Fd ep0;
  Fd bulk_in;   // ep1: controller -> host
  Fd bulk_out;  // ep2: host -> controller
};

std::string explain_endpoint_error(long error) {
  switch (-error) {
    case ESHUTDOWN:
    case ECONNRESET:
      return "the host disabled the USB function (cable unplugged, host reset or gadget unbound)";
    case ENODEV:
      return "the USB function is gone (FunctionFS unmounted or gadget removed)";
    default:
      return errno_text(static_cast<int>(-error));
  }
}

class FfsLink final : public ByteLink {
 public:
  FfsLink(std::shared_ptr<FfsFunction> function, std::shared_ptr<std::atomic<bool>> in_use)
      : in_use_{std::move(in_use)},
        function_(std::move(function)),
        reader_(function_->bulk_out.get(), function_->uri + " (ep2)"),
        writer_(function_->bulk_in.get(), function_->uri + " (ep1)") {
    int pipe_fds[2];
    if (::pipe2(pipe_fds, O_CLOEXEC | O_NONBLOCK) != 0) {
      throw LinkClosed(fmt::format("{}: pipe: {}", function_->uri, errno_text(errno)));
    }
    wake_read_ = std::make_unique<Fd>(pipe_fds[0]);
    wake_write_ = std::make_unique<Fd>(pipe_fds[1]);
  }

  std::size_t read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) override {
    const std::lock_guard lock(read_mutex_);
    if (pending_begin_ < pending_.size()) return take_pending(buffer);
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      if (closed_) throw LinkClosed(fmt::format("{}: link closed", describe()));
      if (!reader_.in_flight()) reader_.submit_read();
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      switch (reader_.wait(std::max(left, 0ms), wake_read_->get())) {
        case AioRequest::Wait::kTimeout:
          return 0;  // the read stays in flight for the next call: no data is lost
        case AioRequest::Wait::kWoken:
          throw LinkClosed(fmt::format("{}: link closed", describe()));
        case AioRequest::Wait::kDone:
          break;
      }
      const long result = reader_.result();
      if (result < 0) throw LinkClosed(fmt::format("{}: {}", describe(), explain_endpoint_error(result)));
      if (result > 0) {
        pending_.assign(reader_.data(), reader_.data() + result);
        pending_begin_ = 0;
        return take_pending(buffer);
      }
      if (std::chrono::steady_clock::now() >= deadline) return 0;  // a zero-length packet
    }
  }

  void write(std::span<const std::uint8_t> bytes) override {
    const std::lock_guard lock(write_mutex_);
    std::size_t done = 0;
    while (done < bytes.size()) {
      if (closed_) throw LinkClosed(fmt::format("{}: link closed", describe()));
      const std::size_t chunk = std::min(writer_.capacity(), bytes.size() - done);
      writer_.submit_write(bytes.subspan(done, chunk));
      const auto outcome = writer_.wait(kWriteTimeout, wake_read_->get());
      if (outcome != AioRequest::Wait::kDone) {
        writer_.cancel();
        throw LinkClosed(
            outcome == AioRequest::Wait::kWoken
                ? fmt::format("{}: link closed", describe())
                : fmt::format("{}: the host took no data for {} s (is a host program reading?)", describe(),
                              std::chrono::duration_cast<std::chrono::seconds>(kWriteTimeout).count()));
      }
      const long result = writer_.result();
      if (result <= 0) {
        throw LinkClosed(
            fmt::format("{}: {}", describe(),
                        result == 0 ? "the endpoint took no data" : explain_endpoint_error(result)));
      }
      done += static_cast<std::size_t>(result);
    }
  }

  void shutdown() override {
    if (closed_.exchange(true)) return;
    const std::uint8_t one = 1;
    [[maybe_unused]] const ssize_t n = ::write(wake_write_->get(), &one, 1);
  }

  std::string describe() const override { return fmt::format("{} (USB function)", function_->uri); }

 private:
  std::size_t take_pending(std::span<std::uint8_t> buffer) {
    const std::size_t n = std::min(buffer.size(), pending_.size() - pending_begin_);
    std::copy_n(pending_.begin() + static_cast<std::ptrdiff_t>(pending_begin_), n, buffer.begin());
    pending_begin_ += n;
    return n;
  }

  // Cleared last (members are destroyed in reverse order): once the listener
  // sees the link gone, its AIO requests are finished and its files idle.
  struct InUse {
    std::shared_ptr<std::atomic<bool>> flag;
    ~InUse() {
      if (flag) flag->store(false);
    }
  } in_use_;
  std::shared_ptr<FfsFunction> function_;
  AioRequest reader_;
  AioRequest writer_;
  std::unique_ptr<Fd> wake_read_;
  std::unique_ptr<Fd> wake_write_;
  std::vector<std::uint8_t> pending_;
  std::size_t pending_begin_ = 0;
  std::mutex read_mutex_;
  std::mutex write_mutex_;
  std::atomic<bool> closed_{false};
};

void write_blob(int fd, const std::vector<std::uint8_t>& blob, const std::string& what,
                const std::string& uri) {
  const ssize_t n = ::write(fd, blob.data(), blob.size());
  if (n != static_cast<ssize_t>(blob.size())) {
    throw LinkClosed(
        fmt::format("{}: FunctionFS refused our {}: {}", uri, what,
                    n < 0 ? errno_text(errno) : fmt::format("wrote {} of {} bytes", n, blob.size())));
  }
}

Fd open_endpoint(const std::string& path, const std::string& uri) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) throw LinkClosed(fmt::format("{}: cannot open {}: {}", uri, path, errno_text(errno)));
  return Fd(fd);
}

class FfsListener final : public LinkListener {
 public:
  explicit FfsListener(std::shared_ptr<FfsFunction> function) : function_(std::move(function)) {}

  std::unique_ptr<ByteLink> accept(std::chrono::milliseconds timeout) override {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    handle_events(0ms);  // a DISABLE already queued must not hand out a dead link
    for (;;) {
      if (enabled_ && !in_use_->load()) {
        in_use_->store(true);
        return std::make_unique<FfsLink>(function_, in_use_);
      }
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      if (left <= 0ms) return nullptr;
      // While a link is in use, come back now and then: it may be destroyed meanwhile.
      handle_events(std::min(left, in_use_->load() ? std::chrono::milliseconds(50) : left));
    }
  }

  std::string describe() const override { return function_->uri; }

 private:
  // Reads and answers ep0 events, waiting up to `timeout` for the first.
  void handle_events(std::chrono::milliseconds timeout) {
    pollfd fd{function_->ep0.get(), POLLIN, 0};
    const int ready = ::poll(&fd, 1, static_cast<int>(timeout.count()));
    if (ready <= 0 || !(fd.revents & POLLIN)) return;
    usb_functionfs_event events[4];
    const ssize_t n = ::read(function_->ep0.get(), events, sizeof events);
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) return;
      throw LinkClosed(fmt::format("{}: reading ep0 events: {}", function_->uri, errno_text(errno)));
    }
    for (std::size_t i = 0; i < static_cast<std::size_t>(n) / sizeof(usb_functionfs_event); ++i) {
      switch (events[i].type) {
        case FUNCTIONFS_ENABLE:  // the host configured the device: endpoints are live
          enabled_ = true;
          break;
        case FUNCTIONFS_DISABLE:  // unplugged, reset or reconfigured
        case FUNCTIONFS_UNBIND:   // the gadget was unbound from the UDC
          enabled_ = false;
          break;
        case FUNCTIONFS_SETUP:
          stall(events[i].u.setup);
          break;
        default:  // BIND, SUSPEND, RESUME: nothing to do
          break;
      }
    }
  }

  // The interface defines no control requests. FunctionFS stalls a request
  // when ep0 is used in the direction opposite to its data stage.
  void stall(const usb_ctrlrequest& setup) {
    std::uint8_t none = 0;
    if (setup.bRequestType & USB_DIR_IN) {
      [[maybe_unused]] const ssize_t n = ::read(function_->ep0.get(), &none, 0);
    } else {
      [[maybe_unused]] const ssize_t n = ::write(function_->ep0.get(), &none, 0);
    }
  }

  std::shared_ptr<FfsFunction> function_;
  bool enabled_ = false;
  std::shared_ptr<std::atomic<bool>> in_use_ = std::make_shared<std::atomic<bool>>(false);
};

}  // namespace

std::unique_ptr<LinkListener> listen_ffs_link(const std::string& uri) {
  const std::string prefix = std::string(kFfsScheme) + ":";
  if (uri.rfind(prefix, 0) != 0) fail("'{}' is not an ffs: URI (expected ffs:/dev/usb-ffs/lightstage)", uri);
  auto function = std::make_shared<FfsFunction>();
  function->uri = uri;
  function->mount = uri.substr(prefix.size());
  const std::string& mount = function->mount;
  if (mount.empty()) fail("'{}': no mount point (expected ffs:/dev/usb-ffs/lightstage)", uri);
  struct stat info {};
  if (::stat(mount.c_str(), &info) != 0) {
    fail(
        "'{}': {} does not exist: create the FunctionFS function and mount it there first "
        "(hw/gadget/lightstage-gadget.sh, hw/docs/links.md)",
        uri, mount);
  }
  if (!S_ISDIR(info.st_mode))
    fail("'{}': {} is not a directory (expected a FunctionFS mount point)", uri, mount);
  const std::string ep0 = mount + "/ep0";
  const int ep0_fd = ::open(ep0.c_str(), O_RDWR | O_CLOEXEC);
  if (ep0_fd < 0) {
    if (errno == ENOENT) {
      fail("'{}': {} is not a FunctionFS mount (no ep0; mount -t functionfs lightstage {})", uri, mount,
           mount);
    }
    throw LinkClosed(fmt::format("{}: cannot open {}: {}{}", uri, ep0, errno_text(errno),
                                 errno == EBUSY ? " (another program serves this function)" : ""));
  }
  function->ep0 = Fd(ep0_fd);
  write_blob(function->ep0.get(), ffs_descriptors(), "USB descriptors", uri);
  write_blob(function->ep0.get(), ffs_strings(), "USB strings", uri);
  // The endpoint files exist once descriptors and strings are in.
  function->bulk_in = open_endpoint(mount + "/ep1", uri);
  function->bulk_out = open_endpoint(mount + "/ep2", uri);
  return std::make_unique<FfsListener>(std::move(function));
}

}  // namespace lightstage::hw
