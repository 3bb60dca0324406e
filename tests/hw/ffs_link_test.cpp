// ffs: links against a stand-in for a FunctionFS mount: a folder whose ep0,
// ep1 and ep2 are FIFOs. The test plays the kernel: it reads what the link
// writes to ep0 (descriptors, strings), feeds it ep0 events (BIND, ENABLE,
// DISABLE, SETUP) and moves bytes through ep1/ep2, which the link drives with
// Linux AIO as it would the real endpoint files. (What only real hardware can
// show, a transfer failing with ESHUTDOWN on DISABLE, is not covered here.)
#include "lightstage/hw/ffs_link.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/framing.hpp"
#include "lightstage/common/message_channel.hpp"
#include "lightstage/hw/ffs_descriptors.hpp"
#include "lightstage/proto/controller.pb.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/aio_abi.h>
#include <linux/usb/functionfs.h>
#include <poll.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

namespace lightstage::hw {
namespace {

using namespace std::chrono_literals;
using Bytes = std::vector<std::uint8_t>;

static_assert(sizeof(usb_functionfs_event) == 12, "the ep0 event layout of linux/usb/functionfs.h");

class FakeFunctionFs {
 public:
  FakeFunctionFs() {
    static std::atomic<int> counter{0};
    dir_ = std::filesystem::temp_directory_path() /
           ("lightstage-ffs-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    std::filesystem::create_directories(dir_);
    for (int i = 0; i < 3; ++i) {
      const std::string path = (dir_ / ("ep" + std::to_string(i))).string();
      EXPECT_EQ(::mkfifo(path.c_str(), 0600), 0) << path << ": " << std::strerror(errno);
      // O_RDWR: opening never blocks, and the link's own opens find a peer.
      fds_[i] = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
      EXPECT_GE(fds_[i], 0) << path;
    }
  }
  ~FakeFunctionFs() {
    for (const int fd : fds_) ::close(fd);
    std::filesystem::remove_all(dir_);
  }
  FakeFunctionFs(const FakeFunctionFs&) = delete;
  FakeFunctionFs& operator=(const FakeFunctionFs&) = delete;

  std::string uri() const { return "ffs:" + dir_.string(); }

  // Everything written to endpoint `ep` so far (the FIFO is drained).
  Bytes take(int ep) {
    Bytes out;
    std::uint8_t buffer[4096];
    for (;;) {
      const ssize_t n = ::read(fds_[ep], buffer, sizeof buffer);
      if (n <= 0) break;
      out.insert(out.end(), buffer, buffer + n);
    }
    return out;
  }
  void put(int ep, const Bytes& bytes) {
    ASSERT_EQ(::write(fds_[ep], bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  }

  void event(std::uint8_t type, std::uint8_t request_type = 0) {
    usb_functionfs_event event{};
    event.type = type;
    event.u.setup.bRequestType = request_type;
    ASSERT_EQ(::write(fds_[0], &event, sizeof event), static_cast<ssize_t>(sizeof event));
  }

 private:
  std::filesystem::path dir_;
  int fds_[3] = {-1, -1, -1};
};

Bytes concat(const Bytes& a, const Bytes& b) {
  Bytes out = a;
  out.insert(out.end(), b.begin(), b.end());
  return out;
}

// Links move data with the kernel's AIO calls, which qemu's user-mode emulator
// (the arm64 cross build's test runner) does not implement.
bool kernel_aio_available() {
  aio_context_t context = 0;
  if (::syscall(SYS_io_setup, 1, &context) != 0) return errno != ENOSYS;
  ::syscall(SYS_io_destroy, context);
  return true;
}
#define SKIP_WITHOUT_KERNEL_AIO() \
  if (!kernel_aio_available()) GTEST_SKIP() << "io_setup: ENOSYS (an emulator without kernel AIO)"

// A listener on a fake mount whose ep0 output has been checked and drained.
std::unique_ptr<LinkListener> listen(FakeFunctionFs& ffs) {
  auto listener = listen_ffs_link(ffs.uri());
  EXPECT_EQ(ffs.take(0), concat(ffs_descriptors(), ffs_strings())) << "descriptors, then strings, on ep0";
  return listener;
}

TEST(FfsLink, WritesDescriptorsThenStringsToEp0) {
  FakeFunctionFs ffs;
  auto listener = listen(ffs);
  EXPECT_EQ(listener->describe(), ffs.uri());
}

TEST(FfsLink, NoLinkUntilTheHostEnablesTheFunction) {
  SKIP_WITHOUT_KERNEL_AIO();
  FakeFunctionFs ffs;
  auto listener = listen(ffs);
  EXPECT_EQ(listener->accept(20ms), nullptr);
  ffs.event(FUNCTIONFS_BIND);
  EXPECT_EQ(listener->accept(20ms), nullptr);
  ffs.event(FUNCTIONFS_ENABLE);
  EXPECT_NE(listener->accept(5s), nullptr);
}

TEST(FfsLink, LinkCarriesFramesBothWays) {
  SKIP_WITHOUT_KERNEL_AIO();
  FakeFunctionFs ffs;
  auto listener = listen(ffs);
  ffs.event(FUNCTIONFS_BIND);
  ffs.event(FUNCTIONFS_ENABLE);
  auto link = listener->accept(5s);
  ASSERT_NE(link, nullptr);
  EXPECT_NE(link->describe().find(ffs.uri()), std::string::npos);
  MessageChannel channel(std::move(link));

  // Host -> controller: bulk OUT is ep2. (Data is put in before each read:
  // a FIFO, unlike an endpoint, would hold an empty read inside io_submit.)
  proto::HostMessage hello;
  hello.set_request_id(1);
  hello.mutable_hello()->set_protocol_version(1);
  const std::string bytes = hello.SerializeAsString();
  ffs.put(2, protocol::encode_frame(
                 std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size())));
  proto::HostMessage received;
  ASSERT_TRUE(channel.receive(received, 5s));
  EXPECT_EQ(received.hello().protocol_version(), 1u);

  // Controller -> host: bulk IN is ep1.
  proto::ControllerMessage info;
  info.set_request_id(1);
  info.mutable_info()->set_rig_name("sim-dome");
  channel.send(info);
  const std::string sent = info.SerializeAsString();
  EXPECT_EQ(ffs.take(1), protocol::encode_frame(
                             std::span(reinterpret_cast<const std::uint8_t*>(sent.data()), sent.size())));
}

TEST(FfsLink, OneLinkAtATimeAndAgainAfterItIsGone) {
  SKIP_WITHOUT_KERNEL_AIO();
  FakeFunctionFs ffs;
  auto listener = listen(ffs);
  ffs.event(FUNCTIONFS_ENABLE);
  auto first = listener->accept(5s);
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(listener->accept(20ms), nullptr) << "a second link while the first is in use";
  first.reset();
  EXPECT_NE(listener->accept(5s), nullptr);
}

TEST(FfsLink, DisableStopsLinksUntilTheNextEnable) {
  SKIP_WITHOUT_KERNEL_AIO();
  FakeFunctionFs ffs;
  auto listener = listen(ffs);
  ffs.event(FUNCTIONFS_ENABLE);
  auto link = listener->accept(5s);
  ASSERT_NE(link, nullptr);
  ffs.event(FUNCTIONFS_DISABLE);
  link.reset();
  EXPECT_EQ(listener->accept(30ms), nullptr) << "a link handed out while the function is disabled";
  ffs.event(FUNCTIONFS_ENABLE);
  EXPECT_NE(listener->accept(5s), nullptr);
  // UNBIND (the gadget taken off the UDC) disables as well.
  ffs.event(FUNCTIONFS_UNBIND);
  EXPECT_EQ(listener->accept(30ms), nullptr);
}

TEST(FfsLink, ControlRequestsAreAnsweredAndEventsKeepFlowing) {
  SKIP_WITHOUT_KERNEL_AIO();
  FakeFunctionFs ffs;
  auto listener = listen(ffs);
  ffs.event(FUNCTIONFS_SETUP, 0xc1);  // vendor IN request to the interface: stalled
  ffs.event(FUNCTIONFS_SETUP, 0x41);  // vendor OUT request: stalled
  ffs.event(FUNCTIONFS_SUSPEND);
  ffs.event(FUNCTIONFS_RESUME);
  ffs.event(FUNCTIONFS_ENABLE);
  EXPECT_NE(listener->accept(5s), nullptr);
}

TEST(FfsLink, LinkAfterShutdownThrowsLinkClosed) {
  SKIP_WITHOUT_KERNEL_AIO();
  FakeFunctionFs ffs;
  auto listener = listen(ffs);
  ffs.event(FUNCTIONFS_ENABLE);
  auto link = listener->accept(5s);
  ASSERT_NE(link, nullptr);
  link->shutdown();
  std::uint8_t buffer[16];
  EXPECT_THROW(link->read(buffer, 10ms), LinkClosed);
  const Bytes bytes = {1, 2, 3};
  EXPECT_THROW(link->write(bytes), LinkClosed);
}

}  // namespace
}  // namespace lightstage::hw
