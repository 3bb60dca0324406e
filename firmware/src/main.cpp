// lightstage-domed: the dome controller daemon. Serves controller.proto on
// --listen, drives the rig's LEDs, trigger and strobe on --gpio, and keeps the
// LEDs within their limits whatever the host asks.
//
// Exit codes: 0 done (also after SIGINT/SIGTERM, with the dome dark);
// 1 runtime failure (link, a GPIO backend that cannot be opened);
// 2 bad command line, rig or URI; 3 --check found a problem with the rig's
// lines on the chip, or could not open the chip; 4 the GPIO backend failed
// while serving (the LEDs were switched off as far as it still allowed):
// systemd's Restart= and the unit's ExecStopPost --dark take over.
#include "lightstage/common/clock.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/common/socket_link.hpp"
#include "lightstage/common/version.hpp"
#include "lightstage/firmware/controller.hpp"
#include "lightstage/firmware/controller_server.hpp"
#include "lightstage/firmware/dome_io.hpp"
#include "lightstage/firmware/gpio_uri.hpp"
#include "lightstage/firmware/realtime.hpp"
#include "lightstage/firmware/rig_lines.hpp"
#include "lightstage/hw/backends.hpp"

#if __has_include("lightstage/hw/links.hpp")
#include "lightstage/hw/links.hpp"
#define LIGHTSTAGE_DOMED_HW_LINKS 1
#endif

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <iostream>

namespace {

namespace fw = lightstage::firmware;

constexpr int kExitCheckFailed = 3;
constexpr int kExitGpioLost = 4;

struct DaemonSettings {
  unsigned watchdog_ms = 1000;
  unsigned hello_timeout_ms = 5000;
  unsigned idle_lease_ms = 30'000;
  double cutoff_margin_us = 2000;
  bool realtime = true;
};

std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "set from a signal handler");

extern "C" void on_stop_signal(int /*signal*/) { g_stop = true; }

void install_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  std::signal(SIGPIPE, SIG_IGN);  // a vanished host is a LinkClosed, not a death
}

std::unique_ptr<lightstage::LinkListener> listen_on(const std::string& uri) {
#ifdef LIGHTSTAGE_DOMED_HW_LINKS
  return lightstage::hw::listen_link(uri);
#else
  return lightstage::listen_socket_link(uri);
#endif
}

// The URI a host connects to: a tcp: listener on port 0 reports the port it got.
std::string listening_uri(const lightstage::LinkListener& listener, const std::string& asked) {
  if (asked.rfind("tcp:", 0) == 0 || asked.rfind("unix:", 0) == 0) {
    try {
      return lightstage::bound_uri(listener);
    } catch (const std::exception&) {
    }
  }
  return listener.describe();
}

void print_rig_summary(const lightstage::Rig& rig, const std::string& rig_path) {
  double shortest_on = 1e300;
  double lowest_duty = 1;
  for (const auto& led : rig.leds) {
    shortest_on = std::min(shortest_on, led.limits.max_on_us);
    lowest_duty = std::min(lowest_duty, led.limits.max_duty);
  }
  fmt::print("{}: rig '{}' is valid: {} LEDs, {} shift-register chain(s), trigger {}{}\n", rig_path, rig.name,
             rig.leds.size(), rig.chains.size(), rig.trigger.line.describe(),
             rig.strobe ? ", strobe " + rig.strobe->line.describe() : std::string());
  fmt::print("limits: max on-time {:.0f} us, max duty {:.2f} (tightest over all LEDs)\n", shortest_on,
             lowest_duty);
}

// --check against a chip: every line exists and is free.
int check_lines(const lightstage::Rig& rig, const std::string& gpio_uri) {
  std::unique_ptr<lightstage::gpio::Chip> chip;
  lightstage::gpio::ChipInfo info;
  try {
    chip = fw::open_gpio_chip(gpio_uri);
    info = chip->info();
  } catch (const lightstage::InputError&) {
    throw;  // a malformed URI is a command-line error (2)
  } catch (const std::exception& e) {
    // No chip is the first missing line.
    fmt::print("{}: cannot open the chip: {}\n1 problem(s)\n", gpio_uri, e.what());
    return kExitCheckFailed;
  }
  int problems = 0;
  int leds_ok = 0;
  fmt::print("{}: chip \"{}\", {} lines\n", gpio_uri, info.label, info.line_names.size());
  for (const fw::LineCheck& check : fw::check_rig_lines(rig, info)) {
    const bool led_line = check.line.use.rfind("LED ", 0) == 0;
    if (led_line && check.problem.empty()) {
      ++leds_ok;  // summarised below: a dome has many
      continue;
    }
    const std::string where = check.offset ? fmt::format("offset {}", *check.offset) : "-";
    fmt::print("  {:28} {:22} {:12} {}\n", check.line.use, check.line.line.describe(), where,
               check.problem.empty() ? "ok" : check.problem);
    if (!check.problem.empty()) ++problems;
  }
  if (leds_ok > 0) fmt::print("  {} LED line(s) ok\n", leds_ok);
  fmt::print("{}\n",
             problems ? fmt::format("{} problem(s)", problems) : std::string("all lines present and free"));
  return problems ? kExitCheckFailed : 0;
}

int run_daemon(const lightstage::Rig& rig, const std::string& gpio_uri, const std::string& listen_uri,
               const DaemonSettings& settings) {
  auto log = lightstage::logger("firmware");
  fw::ControllerOptions options;
  options.realtime = settings.realtime;
  options.cutoff_margin_us = settings.cutoff_margin_us;
  if (settings.realtime) {
    const fw::RealtimeResult locked = fw::lock_memory();
    options.memory_locked = locked.ok;
    if (!locked.ok) log->warn("memory not locked: {}; page faults may delay deadlines", locked.problem);
  }
  lightstage::MonotonicClock clock;
  const auto chip = fw::open_gpio_chip(gpio_uri);
  fw::Controller controller(rig, fw::open_dome_io(rig, *chip, clock), clock, options);
  const auto listener = listen_on(listen_uri);
  fw::ServerOptions server_options;
  server_options.default_watchdog_ms = settings.watchdog_ms;
  server_options.max_watchdog_ms = std::max<unsigned>(server_options.max_watchdog_ms, settings.watchdog_ms);
  server_options.gpio_uri = gpio_uri;
  server_options.hello_timeout = std::chrono::milliseconds(settings.hello_timeout_ms);
  server_options.idle_lease = std::chrono::milliseconds(settings.idle_lease_ms);
  fw::ControllerServer server(controller, server_options);
  log->info("rig '{}' on {}: {} LEDs, strobe {}, real-time {}", rig.name, gpio_uri, rig.leds.size(),
            controller.has_strobe() ? "yes" : "no", controller.realtime() ? "yes" : "no");
  fmt::print("lightstage-domed: listening on {}\n", listening_uri(*listener, listen_uri));
  std::fflush(stdout);
  server.serve(*listener, g_stop);
  if (const auto failure = controller.gpio_failure()) {
    std::cerr << "lightstage-domed: the GPIO backend failed: " << *failure << "\n";
    log->critical("exiting with status {}: GPIO backend lost", kExitGpioLost);
    return kExitGpioLost;
  }
  log->info("stopped by signal; every LED dark");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"lightstage-domed: sequences a dome's LEDs and camera trigger, within hard safety limits."};
  std::string rig_path = lightstage::default_rig_path().string();
  std::string gpio_uri;
  std::string listen_uri;
  DaemonSettings settings;
  std::string log_level = "info";
  bool check = false;
  bool dark = false;
  bool version = false;
  bool no_realtime = false;
  app.add_option("--rig", rig_path, "rig description (YAML)")->capture_default_str();
  app.add_option("--gpio", gpio_uri,
                 "GPIO backend: gpiod:CHIP (path, name, label or a line name) or sim:SOCKET");
  app.add_option("--listen", listen_uri,
                 "where hosts connect: tcp:HOST:PORT, unix:PATH, serial:DEV, ffs:DIR");
  app.add_option("--watchdog-ms", settings.watchdog_ms, "heartbeat timeout when the host asks for none")
      ->capture_default_str()
      ->check(CLI::Range(20u, 60'000u));
  app.add_option("--hello-timeout-ms", settings.hello_timeout_ms,
                 "hang up on a connection that has not sent Hello within this")
      ->capture_default_str()
      ->check(CLI::Range(100u, 600'000u));
  app.add_option("--idle-lease-ms", settings.idle_lease_ms,
                 "hang up on (and darken for) a host that sends no valid message for this long "
                 "(at least its watchdog timeout)")
      ->capture_default_str()
      ->check(CLI::Range(100u, 3'600'000u));
  app.add_option("--cutoff-margin-us", settings.cutoff_margin_us,
                 "switch a static LED off this long before its on-time limit (late wake-ups)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error, off")->capture_default_str();
  app.add_flag("--check", check, "validate the rig (and, with --gpio, its lines on the chip), then exit");
  app.add_flag("--dark", dark, "drive every LED line of the rig inactive on --gpio, then exit");
  app.add_flag("--no-realtime", no_realtime, "do not try SCHED_FIFO and mlockall");
  app.add_flag("--version", version, "print the version and the hardware backends built in");
  CLI11_PARSE(app, argc, argv);
  try {
    if (version) {
      fmt::print("lightstage-domed {} (protocol {}..{})\n", lightstage::kVersion, fw::kMinProtocolVersion,
                 fw::kProtocolVersion);
      for (const auto& backend : lightstage::hw::hardware_backends()) {
        fmt::print("  {:10} {:40} {}\n", backend.scheme + ":", backend.what,
                   backend.built ? "built" : "not built");
      }
      return 0;
    }
    lightstage::set_log_level(log_level);
    install_signal_handlers();
    const lightstage::Rig rig = lightstage::load_rig(rig_path);
    if (check) {
      print_rig_summary(rig, rig_path);
      return gpio_uri.empty() ? 0 : check_lines(rig, gpio_uri);
    }
    if (gpio_uri.empty()) {
      std::cerr << "lightstage-domed: --gpio is required (gpiod:CHIP or sim:SOCKET)\n";
      return 2;
    }
    if (dark) {
      lightstage::MonotonicClock clock;
      const auto chip = fw::open_gpio_chip(gpio_uri);
      fmt::print("lightstage-domed: {} on {}\n", fw::drive_leds_dark(rig, *chip, clock), gpio_uri);
      return 0;
    }
    if (listen_uri.empty()) {
      std::cerr << "lightstage-domed: --listen is required (tcp:HOST:PORT, unix:PATH, serial:DEV, ffs:DIR)\n";
      return 2;
    }
    settings.realtime = !no_realtime;
    return run_daemon(rig, gpio_uri, listen_uri, settings);
  } catch (const lightstage::InputError& e) {
    std::cerr << "lightstage-domed: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    // The controller's destructor has already darkened the dome on the way here.
    std::cerr << "lightstage-domed: " << e.what() << "\n";
    return 1;
  }
}
