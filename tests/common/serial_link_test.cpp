// serial: links over a pseudo-terminal pair. The link opens the pty's slave
// side as it would /dev/ttyACM0 or /dev/ttyGS0; the test plays the other end
// of the cable on the master side.
#include "lightstage/common/serial_link.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/framing.hpp"
#include "lightstage/common/message_channel.hpp"
#include "lightstage/proto/controller.pb.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

namespace lightstage {
namespace {

using namespace std::chrono_literals;
using Bytes = std::vector<std::uint8_t>;

// The far end of the "cable": a pty master, whose slave the link opens.
class PtyCable {
 public:
  PtyCable() {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (master_ < 0 || ::grantpt(master_) != 0 || ::unlockpt(master_) != 0) {
      ADD_FAILURE() << "cannot create a pty: " << std::strerror(errno);
      return;
    }
    slave_path_ = ::ptsname(master_);
  }
  ~PtyCable() { hang_up(); }
  PtyCable(const PtyCable&) = delete;
  PtyCable& operator=(const PtyCable&) = delete;

  std::string uri() const { return "serial:" + slave_path_; }
  const std::string& slave_path() const { return slave_path_; }
  int master() const { return master_; }

  void send(const Bytes& bytes) {
    std::size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::write(master_, bytes.data() + done, bytes.size() - done);
      ASSERT_GT(n, 0) << std::strerror(errno);
      done += static_cast<std::size_t>(n);
    }
  }
  // Reads exactly `count` bytes, or fewer if none arrive for `patience`.
  Bytes receive(std::size_t count, std::chrono::milliseconds patience = 5s) {
    Bytes out;
    while (out.size() < count) {
      pollfd fd{master_, POLLIN, 0};
      if (::poll(&fd, 1, static_cast<int>(patience.count())) <= 0) break;
      std::uint8_t buffer[4096];
      const ssize_t n = ::read(master_, buffer, std::min(sizeof buffer, count - out.size()));
      if (n <= 0) break;
      out.insert(out.end(), buffer, buffer + n);
    }
    return out;
  }
  void hang_up() {
    if (master_ >= 0) ::close(master_);
    master_ = -1;
  }

 private:
  int master_ = -1;
  std::string slave_path_;
};

Bytes frame_of(const google::protobuf::MessageLite& message) {
  const std::string bytes = message.SerializeAsString();
  return protocol::encode_frame(std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
}

TEST(SerialUri, ParsesDeviceBaudAndFlowControl) {
  const SerialOptions plain = parse_serial_uri("serial:/dev/ttyACM0");
  EXPECT_EQ(plain.device, "/dev/ttyACM0");
  EXPECT_EQ(plain.baud, 115200u);
  EXPECT_FALSE(plain.hardware_flow_control);
  const SerialOptions full = parse_serial_uri("serial:/dev/ttyUSB1,921600,rtscts");
  EXPECT_EQ(full.device, "/dev/ttyUSB1");
  EXPECT_EQ(full.baud, 921600u);
  EXPECT_TRUE(full.hardware_flow_control);
}

TEST(SerialUri, ErrorsNameTheUriAndTheBadPart) {
  const auto message_of = [](const std::string& uri) {
    try {
      parse_serial_uri(uri);
    } catch (const InputError& error) {
      return std::string(error.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message_of("serial:").find("no device"), std::string::npos);
  EXPECT_NE(message_of("serial:,9600").find("no device"), std::string::npos);
  EXPECT_NE(message_of("serial:/dev/ttyS0,12345").find("unsupported baud rate 12345"), std::string::npos);
  EXPECT_NE(message_of("serial:/dev/ttyS0,12345").find("115200"), std::string::npos);  // lists the choices
  EXPECT_NE(message_of("serial:/dev/ttyS0,fast").find("unknown option 'fast'"), std::string::npos);
  EXPECT_NE(message_of("serial:/dev/ttyS0,9600,19200").find("twice"), std::string::npos);
  EXPECT_NE(message_of("serial:/dev/ttyS0,").find("unknown option ''"), std::string::npos);
  EXPECT_NE(message_of("tcp:1.2.3.4:5").find("not a serial: URI"), std::string::npos);
  EXPECT_NE(message_of("serial:/dev/ttyS0,fast").find("serial:/dev/ttyS0,fast"), std::string::npos);
}

TEST(SerialLink, PutsTheLineInRawMode) {
  PtyCable cable;
  auto link = open_serial_link(cable.uri());
  termios tio{};
  ASSERT_EQ(::tcgetattr(cable.master(), &tio), 0);  // a pty master reports its slave's settings
  EXPECT_EQ(tio.c_lflag & (ICANON | ECHO | ISIG | IEXTEN), 0u);
  EXPECT_EQ(tio.c_iflag & (IXON | IXOFF | ICRNL | INLCR | ISTRIP), 0u);
  EXPECT_EQ(tio.c_oflag & OPOST, 0u);
  EXPECT_EQ(tio.c_cflag & CSIZE, static_cast<tcflag_t>(CS8));
  EXPECT_EQ(tio.c_cflag & (PARENB | CRTSCTS), 0u);
  EXPECT_EQ(cfgetospeed(&tio), static_cast<speed_t>(B115200));
  EXPECT_NE(link->describe().find(cable.slave_path()), std::string::npos) << link->describe();
}

TEST(SerialLink, FramesPassBothWaysByteForByte) {
  PtyCable cable;
  MessageChannel channel(open_serial_link(cable.uri()));

  // Board -> host: the frame arrives exactly as encoded.
  proto::ControllerMessage reply;
  reply.set_request_id(77);
  std::string all;
  for (int i = 0; i < 128; ++i) all.push_back(static_cast<char>(i));  // proto3 strings are UTF-8
  reply.mutable_error()->set_message(all);
  channel.send(reply);
  const Bytes expected = frame_of(reply);
  EXPECT_EQ(cable.receive(expected.size()), expected);

  // Host -> board: the message, then a raw frame holding every byte value,
  // including those a cooked tty would eat or translate (^C, ^D, ^S/^Q, CR, LF,
  // DEL), arrive unchanged, and nothing is echoed back.
  proto::ControllerMessage received;
  cable.send(expected);
  ASSERT_TRUE(channel.receive(received, 5s));
  EXPECT_EQ(received.error().message(), all);
  Bytes every_value;
  for (int i = 0; i < 256; ++i) every_value.push_back(static_cast<std::uint8_t>(255 - i));
  const Bytes raw_frame = protocol::encode_frame(every_value);
  cable.send(raw_frame);
  std::uint8_t buffer[1024];
  Bytes got;
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while (got.size() < raw_frame.size() && std::chrono::steady_clock::now() < deadline) {
    const std::size_t n = channel.link().read(buffer, 100ms);
    got.insert(got.end(), buffer, buffer + n);
  }
  EXPECT_EQ(got, raw_frame);
  EXPECT_TRUE(cable.receive(1, 50ms).empty()) << "the line echoed input back";
}

TEST(SerialLink, GarbageAndCorruptFramesAreRejectedWhileTheLinkGoesOn) {
  PtyCable cable;
  MessageChannel channel(open_serial_link(cable.uri()));
  proto::HostMessage good;
  good.set_request_id(5);
  good.mutable_status();
  Bytes corrupt = frame_of(good);
  corrupt[protocol::kHeaderSize + 1] ^= 0x40;
  const std::string noise = "\r\nATZ\r\n";
  Bytes wire(noise.begin(), noise.end());
  wire.insert(wire.end(), corrupt.begin(), corrupt.end());
  const Bytes good_frame = frame_of(good);
  wire.insert(wire.end(), good_frame.begin(), good_frame.end());
  cable.send(wire);

  int errors = 0;
  proto::HostMessage received;
  for (;;) {
    try {
      ASSERT_TRUE(channel.receive(received, 5s));
      break;
    } catch (const ProtocolError& error) {
      ++errors;
      ASSERT_LT(errors, 10) << error.what();
    }
  }
  EXPECT_GE(errors, 1);
  EXPECT_EQ(received.request_id(), 5u);
  EXPECT_TRUE(received.has_status());

  // ...and the line still works both ways.
  proto::ControllerMessage ack;
  ack.set_request_id(5);
  ack.mutable_ack();
  channel.send(ack);
  const Bytes expected = frame_of(ack);
  EXPECT_EQ(cable.receive(expected.size()), expected);
}

TEST(SerialLink, HangUpGivesLinkClosed) {
  PtyCable cable;
  MessageChannel channel(open_serial_link(cable.uri()));
  proto::HostMessage received;
  EXPECT_FALSE(channel.receive(received, 20ms));
  cable.hang_up();
  EXPECT_THROW(
      {
        for (int i = 0; i < 100; ++i) channel.receive(received, 100ms);
      },
      LinkClosed);
}

// Nobody reads the other end (a host with the port closed): the line's
// buffers fill, and the write fails after a while instead of blocking forever.
TEST(SerialLink, WriteThatNobodyTakesFailsInsteadOfBlocking) {
  PtyCable cable;
  auto link = open_serial_link(cable.uri());
  const Bytes lots(1 << 20, 0x55);
  try {
    link->write(lots);
    FAIL() << "a megabyte went into a line nobody reads";
  } catch (const LinkClosed& error) {
    EXPECT_NE(std::string(error.what()).find("took no data"), std::string::npos) << error.what();
  }
}

TEST(SerialLink, ShutdownFromAnotherThreadWakesAReader) {
  PtyCable cable;
  MessageChannel channel(open_serial_link(cable.uri()));
  std::thread stopper([&channel] {
    std::this_thread::sleep_for(50ms);
    channel.link().shutdown();
  });
  proto::HostMessage received;
  EXPECT_THROW(channel.receive(received, 60s), LinkClosed);
  stopper.join();
}

TEST(SerialLink, MissingDeviceIsLinkClosedNamingTheUri) {
  try {
    open_serial_link("serial:/dev/lightstage-no-such-tty");
    FAIL() << "opened a missing device";
  } catch (const LinkClosed& error) {
    EXPECT_NE(std::string(error.what()).find("serial:/dev/lightstage-no-such-tty"), std::string::npos)
        << error.what();
  }
}

TEST(SerialLink, RegularFileIsNotATerminal) {
  const auto path =
      std::filesystem::temp_directory_path() / ("lightstage-not-a-tty-" + std::to_string(::getpid()));
  std::ofstream(path) << "x";
  try {
    open_serial_link("serial:" + path.string());
    ADD_FAILURE() << "opened a regular file";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("not a terminal"), std::string::npos) << error.what();
  }
  std::filesystem::remove(path);
}

TEST(SerialLink, SecondOpenerOfTheSameLineIsRefused) {
  PtyCable cable;
  auto first = open_serial_link(cable.uri());
  try {
    open_serial_link(cable.uri());
    FAIL() << "two links on one line";
  } catch (const LinkClosed& error) {
    EXPECT_NE(std::string(error.what()).find("in use"), std::string::npos) << error.what();
  }
}

TEST(SerialListener, HandsOutTheLineAgainOnlyAfterTheLinkIsGone) {
  PtyCable cable;
  auto listener = listen_serial_link(cable.uri());
  auto first = listener->accept(5s);
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(listener->accept(30ms), nullptr) << "handed out a line that is in use";
  first.reset();
  auto second = listener->accept(5s);
  ASSERT_NE(second, nullptr);
  // The reopened link works.
  const Bytes hello = {'h', 'i'};
  second->write(hello);
  EXPECT_EQ(cable.receive(2), hello);
}

TEST(SerialListener, WaitsForADeviceThatDoesNotExistYet) {
  auto listener = listen_serial_link("serial:/dev/lightstage-not-plugged-yet");
  EXPECT_EQ(listener->accept(30ms), nullptr);
  EXPECT_NE(listener->describe().find("/dev/lightstage-not-plugged-yet"), std::string::npos);
}

TEST(SerialListener, MalformedUriFailsAtOnce) {
  EXPECT_THROW(listen_serial_link("serial:/dev/ttyS0,7"), InputError);
}

}  // namespace
}  // namespace lightstage
