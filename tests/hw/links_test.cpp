// The URI factory: every scheme reaches its backend, and every wrong URI
// (unknown scheme, wrong direction, malformed, backend not built, device or
// mount missing) is refused with a message naming the URI and the way out.
#include "lightstage/hw/links.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/message_channel.hpp"
#include "lightstage/common/socket_link.hpp"
#include "lightstage/hw/backends.hpp"
#include "lightstage/hw/ffs_link.hpp"
#include "lightstage/proto/controller.pb.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <set>
#include <string>
#include <thread>

namespace lightstage::hw {
namespace {

using namespace std::chrono_literals;

// The message of the exception `action` throws, which must be of type E.
template <typename E>
std::string message_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const E& error) {
    return error.what();
  } catch (const std::exception& other) {
    return std::string("wrong exception type: ") + other.what();
  }
  return "no exception";
}

TEST(Links, SchemeTableCoversEveryTransport) {
  std::set<std::string> names;
  for (const auto& scheme : link_schemes()) {
    names.insert(scheme.scheme);
    EXPECT_EQ(scheme.form.rfind(scheme.scheme + ":", 0), 0u) << scheme.form;
    EXPECT_TRUE(scheme.connect || scheme.listen) << scheme.scheme;
  }
  EXPECT_EQ(names, (std::set<std::string>{"tcp", "unix", "serial", "usb", "ffs"}));
}

TEST(Links, UnknownSchemeNamesTheUriAndListsTheSchemes) {
  const std::string message = message_of<InputError>([] { connect_link("bluetooth:00:11:22"); });
  EXPECT_NE(message.find("bluetooth:00:11:22"), std::string::npos) << message;
  EXPECT_NE(message.find("unknown link scheme 'bluetooth'"), std::string::npos) << message;
  for (const char* form : {"tcp:HOST:PORT", "unix:PATH", "serial:DEVICE", "usb:VID:PID"}) {
    EXPECT_NE(message.find(form), std::string::npos) << form << " missing from: " << message;
  }
  EXPECT_EQ(message.find("ffs:"), std::string::npos) << "ffs: cannot connect: " << message;
  const std::string listen = message_of<InputError>([] { listen_link("bluetooth:00:11:22"); });
  EXPECT_NE(listen.find("ffs:MOUNT"), std::string::npos) << listen;
  EXPECT_EQ(listen.find("usb:VID"), std::string::npos) << "usb: cannot listen: " << listen;
}

TEST(Links, UriWithoutSchemeIsRefused) {
  const std::string message = message_of<InputError>([] { connect_link("/dev/ttyACM0"); });
  EXPECT_NE(message.find("'/dev/ttyACM0' is not a link URI"), std::string::npos) << message;
  EXPECT_NE(message_of<InputError>([] { listen_link(""); }).find("not a link URI"), std::string::npos);
}

TEST(Links, WrongDirectionPointsToTheOtherSide) {
  const std::string usb = message_of<InputError>([] { listen_link("usb:1209:0001"); });
  EXPECT_NE(usb.find("controller listens on ffs:"), std::string::npos) << usb;
  const std::string ffs = message_of<InputError>([] { connect_link("ffs:/dev/usb-ffs/lightstage"); });
  EXPECT_NE(ffs.find("host connects with usb:"), std::string::npos) << ffs;
}

TEST(Links, MalformedUrisOfKnownSchemesAreInputErrors) {
  EXPECT_NE(message_of<InputError>([] { connect_link("serial:/dev/ttyS0,7"); }).find("baud"),
            std::string::npos);
  EXPECT_NE(message_of<InputError>([] { listen_link("serial:"); }).find("no device"), std::string::npos);
  EXPECT_NE(message_of<InputError>([] { listen_link("ffs:"); }).find("no mount point"), std::string::npos);
  if (backend_built("usb")) {
    EXPECT_NE(message_of<InputError>([] { connect_link("usb:1209:xyz"); }).find("product ID"),
              std::string::npos);
  }
}

TEST(Links, UsbWithoutLibusbSaysTheBuildLacksIt) {
  if (backend_built("usb")) {
    // With libusb: a missing device, named by VID:PID.
    const std::string message = message_of<LinkClosed>([] { connect_link("usb:1209:0001"); });
    EXPECT_NE(message.find("1209:0001"), std::string::npos) << message;
  } else {
    const std::string message = message_of<Error>([] { connect_link("usb:1209:0001"); });
    EXPECT_NE(message.find("this build has no usb: links"), std::string::npos) << message;
  }
}

TEST(Links, MissingSerialDeviceIsLinkClosedEvenAfterWaiting) {
  const std::string message =
      message_of<LinkClosed>([] { connect_link("serial:/dev/lightstage-no-such-tty", 50ms); });
  EXPECT_NE(message.find("serial:/dev/lightstage-no-such-tty"), std::string::npos) << message;
}

TEST(Links, SerialListenerWaitsForItsDevice) {
  auto listener = listen_link("serial:/dev/lightstage-no-such-tty");
  EXPECT_EQ(listener->accept(20ms), nullptr);
}

TEST(Links, SerialConnectOpensAPty) {
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  ASSERT_GE(master, 0);
  ASSERT_EQ(::grantpt(master), 0);
  ASSERT_EQ(::unlockpt(master), 0);
  const std::string uri = std::string("serial:") + ::ptsname(master) + ",9600";
  auto link = connect_link(uri, 1s);
  const std::uint8_t byte = 0x42;
  link->write(std::span(&byte, 1));
  std::uint8_t got = 0;
  EXPECT_EQ(::read(master, &got, 1), 1);
  EXPECT_EQ(got, byte);
  ::close(master);
}

TEST(Links, FfsOnAMissingMountIsAClearError) {
  const std::string message =
      message_of<InputError>([] { listen_link("ffs:/dev/usb-ffs/lightstage-missing"); });
  EXPECT_NE(message.find("ffs:/dev/usb-ffs/lightstage-missing"), std::string::npos) << message;
  EXPECT_NE(message.find("does not exist"), std::string::npos) << message;
  EXPECT_NE(message.find("lightstage-gadget.sh"), std::string::npos) << message;
}

TEST(Links, FfsOnADirectoryThatIsNotFunctionFsIsAClearError) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("lightstage-not-ffs-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string uri = "ffs:" + dir.string();
  const std::string message = message_of<InputError>([&uri] { listen_link(uri); });
  EXPECT_NE(message.find("is not a FunctionFS mount"), std::string::npos) << message;
  EXPECT_NE(message.find(uri), std::string::npos) << message;
  std::filesystem::remove_all(dir);
  const std::string file_message = message_of<InputError>([] { listen_ffs_link("ffs:/etc/hostname"); });
  EXPECT_NE(file_message.find("not a directory"), std::string::npos) << file_message;
}

// tcp: and unix: reach the socket links: a full round trip through the factory.
TEST(Links, UnixAndTcpRoundTripThroughTheFactory) {
  const auto path =
      std::filesystem::temp_directory_path() / ("lightstage-links-" + std::to_string(::getpid()) + ".sock");
  for (const std::string& uri : {std::string("unix:") + path.string(), std::string("tcp:127.0.0.1:0")}) {
    auto listener = listen_link(uri);
    const std::string bound = bound_uri(*listener);
    std::unique_ptr<ByteLink> accepted;
    std::thread acceptor([&] { accepted = listener->accept(5s); });
    MessageChannel client(connect_link(bound, 5s));
    acceptor.join();
    ASSERT_NE(accepted, nullptr) << uri;
    MessageChannel server(std::move(accepted));
    proto::HostMessage hello;
    hello.set_request_id(1);
    hello.mutable_hello()->set_protocol_version(1);
    client.send(hello);
    proto::HostMessage received;
    ASSERT_TRUE(server.receive(received, 5s)) << uri;
    EXPECT_EQ(received.hello().protocol_version(), 1u) << uri;
  }
}

}  // namespace
}  // namespace lightstage::hw
