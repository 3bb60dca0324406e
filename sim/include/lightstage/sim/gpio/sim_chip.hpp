#pragma once
// The firmware's `sim:` GPIO backend: gpio::Chip over a connection to
// lightstage-sim's virtual chip (sim_gpio.proto).
//
// Line requests, releases and info() wait for the sim's answer; an error from
// the sim becomes a GpioError carrying its message (which names the line and,
// when busy, its consumer). OutputLines::set() is pipelined: it sends the
// change with its timestamp and returns without waiting, so bit-banging a
// shift-register chain costs a write, not a round trip; an error the sim
// reports for a set surfaces as GpioError from the next call. Strobe edges
// arrive unsolicited and queue per line for EdgeInput::wait_until(). A lost
// connection makes every later call throw GpioError.

#include "lightstage/common/gpio.hpp"

#include <chrono>
#include <memory>
#include <string>

namespace lightstage::sim::gpio {

// `address` is "unix:PATH", "tcp:HOST:PORT" or a bare socket path. Waits up to
// `connect_timeout` for the sim to listen. Throws GpioError naming the address.
std::unique_ptr<lightstage::gpio::Chip> connect_sim_chip(
    const std::string& address, std::chrono::milliseconds connect_timeout = std::chrono::milliseconds(2000));

// Arms a fault in a running sim (same text as lightstage-sim --fault), over a
// connection of its own. Throws GpioError with the sim's answer.
void inject_sim_fault(const std::string& address, const std::string& fault);

}  // namespace lightstage::sim::gpio
