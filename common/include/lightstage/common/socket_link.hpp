#pragma once
// Stream-socket links: "tcp:HOST:PORT" and "unix:PATH". POSIX only, so they
// live in common/ and serve the host, the firmware and the simulator alike.
// A TCP listener on port 0 picks a free port (describe() tells which).

#include "lightstage/common/link.hpp"

#include <chrono>
#include <memory>
#include <string>
#include <utility>

namespace lightstage {

// Connects, waiting up to `timeout` for the peer to accept (retrying while a
// Unix socket file does not exist yet or a TCP port refuses). Throws LinkClosed
// naming the URI when it cannot, InputError for a malformed URI.
std::unique_ptr<ByteLink> connect_socket_link(
    const std::string& uri, std::chrono::milliseconds timeout = std::chrono::milliseconds(0));

// Binds and listens. A stale Unix socket file (no one listening) is replaced;
// a live one is an error. The listener removes its socket file when destroyed.
std::unique_ptr<LinkListener> listen_socket_link(const std::string& uri);

// The bound URI of a listener from listen_socket_link (tcp: with the real port).
std::string bound_uri(const LinkListener& listener);

// A connected pair of in-process links (socketpair), for tests and in-process plumbing.
std::pair<std::unique_ptr<ByteLink>, std::unique_ptr<ByteLink>> socket_link_pair();

}  // namespace lightstage
