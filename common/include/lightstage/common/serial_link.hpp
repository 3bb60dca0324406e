#pragma once
// Serial-line links: "serial:/dev/ttyACM0[,BAUD][,rtscts]".
//
// Raw mode (no echo, no line editing, no CR/LF translation, 8N1, no flow
// control unless ",rtscts"), so frames pass byte for byte. The same code runs
// on both ends of a USB CDC-ACM link: the controller board opens its gadget
// side (/dev/ttyGS0), the host the port the board shows up as (/dev/ttyACM*).
// The baud rate matters only on a real UART; CDC-ACM ignores it. POSIX only,
// so it lives in common/ next to the socket links and shares their FdLink.

#include "lightstage/common/link.hpp"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace lightstage {

struct SerialOptions {
  std::string device;                  // e.g. "/dev/ttyACM0"
  std::uint32_t baud = 115200;         // one of serial_baud_rates()
  bool hardware_flow_control = false;  // RTS/CTS, ",rtscts"
};

inline constexpr const char* kSerialScheme = "serial";

// Parses "serial:DEVICE[,BAUD][,rtscts]"; throws InputError naming the URI
// and the bad part.
SerialOptions parse_serial_uri(const std::string& uri);

// The baud rates termios can set, ascending.
const std::vector<std::uint32_t>& serial_baud_rates();

// Opens and configures the line (exclusive: a second opener gets EBUSY).
// Throws InputError for a malformed URI or a device that is not a terminal,
// LinkClosed when the device cannot be opened (missing, permissions).
std::unique_ptr<ByteLink> open_serial_link(const std::string& uri);

// A serial line has no connections to accept: this "listener" hands out the
// one link to the line, and again once that link has been destroyed (a USB
// cable pulled and plugged back makes the old link fail with LinkClosed, the
// next accept() reopens the device). accept() waits while the device does not
// exist yet (a gadget not bound, a board not plugged) or the link is in use.
std::unique_ptr<LinkListener> listen_serial_link(const std::string& uri);

}  // namespace lightstage
