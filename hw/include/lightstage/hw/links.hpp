#pragma once
// Byte links by URI, for the host (connect) and the controller (listen):
//
//   tcp:HOST:PORT           connect, listen   (common/socket_link.hpp)
//   unix:PATH               connect, listen   (common/socket_link.hpp)
//   serial:DEVICE[,BAUD]    connect, listen   (common/serial_link.hpp; a USB CDC-ACM
//                                              gadget: /dev/ttyGS0 on the board,
//                                              /dev/ttyACM* on the host)
//   usb:VID:PID[:SERIAL]    connect only      (usb_link.hpp, libusb; the host side)
//   ffs:MOUNT               listen only       (ffs_link.hpp, FunctionFS; the board side)
//
// hw/docs/links.md tells how to bring each one up on a board.

#include "lightstage/common/link.hpp"

#include <chrono>
#include <memory>
#include <string>
#include <vector>

namespace lightstage::hw {

struct LinkScheme {
  std::string scheme;  // "tcp"
  std::string form;    // "tcp:HOST:PORT"
  bool connect = false;
  bool listen = false;
  bool built = false;   // false: this build lacks the library it needs
  std::string missing;  // what to install when not built
};

// Every scheme this code knows, built or not.
const std::vector<LinkScheme>& link_schemes();

// Opens a link to the peer named by `uri`, waiting up to `timeout` for it to
// appear (a socket to accept, a USB device to be plugged in). Throws InputError
// for a malformed URI, an unknown scheme or one that cannot connect (the
// message names the URI and lists the schemes), Error when this build lacks the
// backend, LinkClosed when the peer is not there.
std::unique_ptr<ByteLink> connect_link(const std::string& uri,
                                       std::chrono::milliseconds timeout = std::chrono::milliseconds(0));

// Starts accepting links on `uri` (errors as for connect_link).
std::unique_ptr<LinkListener> listen_link(const std::string& uri);

}  // namespace lightstage::hw
