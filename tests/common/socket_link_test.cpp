#include "lightstage/common/socket_link.hpp"
#include "lightstage/common/message_channel.hpp"
#include "lightstage/proto/controller.pb.h"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <array>
#include <filesystem>
#include <thread>

namespace lightstage {
namespace {

using std::chrono::milliseconds;

std::string temp_socket(const std::string& name) {
  return (testing::socket_dir() /
          (std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "-" + name))
      .string();
}

proto::HostMessage heartbeat(std::uint64_t n) {
  proto::HostMessage m;
  m.set_request_id(static_cast<std::uint32_t>(n));
  m.mutable_heartbeat()->set_counter(n);
  return m;
}

void round_trip(LinkListener& listener, const std::string& connect_uri) {
  std::unique_ptr<ByteLink> server_side;
  std::thread accepter([&] { server_side = listener.accept(milliseconds(5000)); });
  MessageChannel client(connect_socket_link(connect_uri, milliseconds(2000)));
  accepter.join();
  ASSERT_TRUE(server_side);
  MessageChannel server(std::move(server_side));
  for (std::uint64_t i = 1; i <= 50; ++i) client.send(heartbeat(i));
  for (std::uint64_t i = 1; i <= 50; ++i) {
    proto::HostMessage got;
    ASSERT_TRUE(server.receive(got, milliseconds(2000)));
    EXPECT_EQ(got.heartbeat().counter(), i);
  }
  proto::HostMessage none;
  EXPECT_FALSE(server.receive(none, milliseconds(10)));
}

TEST(SocketLink, UnixRoundTrip) {
  const std::string uri = "unix:" + temp_socket("a.sock");
  auto listener = listen_socket_link(uri);
  round_trip(*listener, uri);
}

TEST(SocketLink, TcpOnAFreePort) {
  auto listener = listen_socket_link("tcp:127.0.0.1:0");
  const std::string uri = bound_uri(*listener);
  ASSERT_TRUE(uri.starts_with("tcp:127.0.0.1:"));
  EXPECT_NE(uri, "tcp:127.0.0.1:0");
  round_trip(*listener, uri);
}

TEST(SocketLink, PeerCloseIsLinkClosed) {
  auto [a, b] = socket_link_pair();
  b.reset();
  std::array<std::uint8_t, 8> buffer{};
  EXPECT_THROW(a->read(buffer, milliseconds(1000)), LinkClosed);
}

TEST(SocketLink, ShutdownWakesABlockedReader) {
  auto [a, b] = socket_link_pair();
  bool closed = false;
  std::thread reader([&, link = a.get()] {
    std::array<std::uint8_t, 8> buffer{};
    try {
      link->read(buffer, milliseconds(30'000));
    } catch (const LinkClosed&) {
      closed = true;
    }
  });
  std::this_thread::sleep_for(milliseconds(20));
  a->shutdown();
  reader.join();
  EXPECT_TRUE(closed);
  EXPECT_THROW(a->write(std::array<std::uint8_t, 1>{1}), LinkClosed);
}

TEST(SocketLink, WritingToAGonePeerThrowsInsteadOfSigpipe) {
  auto [a, b] = socket_link_pair();
  b.reset();
  std::vector<std::uint8_t> big(1 << 16, 7);
  EXPECT_THROW(
      {
        for (int i = 0; i < 64; ++i) a->write(big);
      },
      LinkClosed);
}

TEST(SocketLink, ConnectFailureNamesTheUri) {
  const std::string uri = "unix:" + temp_socket("nobody.sock");
  try {
    connect_socket_link(uri, milliseconds(50));
    FAIL() << "connected to nothing";
  } catch (const LinkClosed& e) {
    EXPECT_NE(std::string(e.what()).find(uri), std::string::npos) << e.what();
  }
}

TEST(SocketLink, ConnectWaitsForALateListener) {
  const std::string uri = "unix:" + temp_socket("late.sock");
  std::unique_ptr<LinkListener> listener;
  std::thread late([&] {
    std::this_thread::sleep_for(milliseconds(100));
    listener = listen_socket_link(uri);
  });
  auto link = connect_socket_link(uri, milliseconds(10'000));
  late.join();
  EXPECT_TRUE(link);
}

TEST(SocketLink, StaleSocketFileIsReplacedLiveOneRefused) {
  const std::string path = temp_socket("stale.sock");
  {
    // Leave a socket file with no listener behind, as a crashed process would.
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::snprintf(addr.sun_path, sizeof(addr.sun_path), "%s", path.c_str());
    ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)), 0);
    ::close(fd);
  }
  ASSERT_TRUE(std::filesystem::exists(path));
  auto listener = listen_socket_link("unix:" + path);
  EXPECT_THROW(listen_socket_link("unix:" + path), LinkClosed);
  listener.reset();
  EXPECT_FALSE(std::filesystem::exists(path)) << "the listener removes its socket file";
}

TEST(SocketLink, MalformedUrisAreInputErrors) {
  EXPECT_THROW(listen_socket_link("tcp:localhost"), InputError);
  EXPECT_THROW(listen_socket_link("tcp:127.0.0.1:99999"), InputError);
  EXPECT_THROW(listen_socket_link("tcp:127.0.0.1:http"), InputError);
  EXPECT_THROW(listen_socket_link("unix:"), InputError);
  EXPECT_THROW(listen_socket_link("unix:/" + std::string(200, 'x')), InputError);
  EXPECT_THROW(connect_socket_link("serial:/dev/ttyACM0"), InputError);
}

}  // namespace
}  // namespace lightstage
