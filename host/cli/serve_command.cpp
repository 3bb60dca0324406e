// `lightstage serve`: the operator's station in a browser (host/station).
#include "commands.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/station/station_server.hpp"

#include <fmt/format.h>

#include <csignal>
#include <thread>

#include <pthread.h>

namespace lightstage::cli {
namespace {

// HOST:PORT, [V6]:PORT or PORT alone (on loopback).
std::pair<std::string, int> parse_listen(const std::string& text) {
  std::string host = "127.0.0.1", port = text;
  if (const auto colon = text.rfind(':'); colon != std::string::npos) {
    host = text.substr(0, colon);
    port = text.substr(colon + 1);
    if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  }
  int number = -1;
  try {
    std::size_t used = 0;
    number = std::stoi(port, &used);
    if (used != port.size()) number = -1;
  } catch (const std::exception&) {
  }
  if (host.empty() || number < 0 || number > 65535)
    fail("--listen: '{}' is not HOST:PORT (e.g. 127.0.0.1:8080, 0.0.0.0:8080)", text);
  return {host, number};
}

}  // namespace

void add_serve(CLI::App& app) {
  struct Args {
    std::string rig = default_rig_path().string();
    std::string controller, camera, listen = "127.0.0.1:8080", data = "station", token;
    bool simulated = false;
    double lease_s = 15;
    station::SimulatedBenchOptions bench;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "serve",
      "Run the operator's station: the dome from a browser.\n"
      "\n"
      "Serves the station's API (and page) on --listen, over the same library the commands use: the "
      "dome's LEDs and status, a camera preview with its histogram and sharpness, captures (planned, "
      "followed, stopped and resumed), light calibration from chrome-sphere captures, solves with their "
      "surfaces and reports. Everything lands in --data: stacks/, calibrations/, results/ and audit.log "
      "(every action, who asked and how it ended).\n"
      "One browser controls the dome at a time (it takes control; others watch read-only); LEDs lit by "
      "hand go dark when that browser goes away. Any --listen address but loopback needs a token: "
      "--token, or one made up and printed at start; open the printed address.\n"
      "--simulated starts the simulated dome's programs (as demo does); the page then places the object "
      "or the chrome sphere under it.\n"
      "\n"
      "Example: lightstage serve --simulated --data station --listen 127.0.0.1:8080");
  sub->add_option("--rig", args->rig, "rig description (YAML)")->capture_default_str();
  sub->add_option("--controller", args->controller, "controller URI: tcp:, unix:, serial:, usb:");
  sub->add_option("--camera", args->camera,
                  "camera URI: v4l2:/dev/videoN, libcamera:ID, aravis:ID, gphoto2:[MODEL|PORT], folder:PATH");
  sub->add_flag("--simulated", args->simulated,
                "start lightstage-sim and lightstage-domed and serve the simulated dome");
  sub->add_option("--listen", args->listen, "address and port to serve on (HOST:PORT; port 0 = any free)")
      ->capture_default_str();
  sub->add_option("--data", args->data, "the station's data folder (created)")->capture_default_str();
  sub->add_option("--token", args->token,
                  "access token every request must carry (default: none on loopback, else made up)");
  sub->add_option("--lease-s", args->lease_s, "seconds without a request before control lapses")
      ->capture_default_str();
  sub->add_option("--scene", args->bench.scene, "--simulated: the object (scene preset or YAML)")
      ->capture_default_str();
  sub->add_option("--material", args->bench.material, "--simulated: material preset overriding the scene's");
  sub->add_option("--width", args->bench.width, "--simulated: image width (default: the rig camera's)");
  sub->add_option("--height", args->bench.height, "--simulated: image height (default: the rig camera's)");
  sub->add_option("--noise", args->bench.noise, "--simulated: sensor noise, none or physical")
      ->capture_default_str();
  sub->add_option(
      "--programs", args->bench.programs,
      "--simulated: folder of lightstage-sim and lightstage-domed (default: beside this program)");
  sub->callback([args] {
    station::StationOptions options;
    options.rig = args->rig;
    options.data = args->data;
    if (args->simulated) {
      if (!args->controller.empty() || !args->camera.empty())
        fail("--simulated starts its own dome: give neither --controller nor --camera");
      options.simulated = args->bench;
    } else {
      if (args->controller.empty() || args->camera.empty())
        fail("serve needs --controller and --camera (or --simulated)");
      options.controller_uri = args->controller;
      options.camera_uri = args->camera;
    }
    if (!(args->lease_s >= 1 && args->lease_s <= 3600))
      fail("--lease-s: {} is not in [1, 3600]", args->lease_s);
    station::ServerOptions server_options;
    std::tie(server_options.host, server_options.port) = parse_listen(args->listen);
    server_options.token = args->token;
    if (server_options.token.empty() && !station::is_loopback_address(server_options.host))
      server_options.token = station::random_token();
    server_options.lease = std::chrono::milliseconds(static_cast<long>(args->lease_s * 1000));

    // SIGINT and SIGTERM end the server on a thread of their own; every other
    // thread (the station's, the server's) is started with them blocked.
    sigset_t signals;
    sigemptyset(&signals);
    sigaddset(&signals, SIGINT);
    sigaddset(&signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &signals, nullptr);

    station::Station station(options);
    station::StationServer server(station, server_options);
    server.bind();
    fmt::print("lightstage serve: the station is at {}\n", server.url());
    std::fflush(stdout);
    std::thread waiter([&] {
      int signal = 0;
      sigwait(&signals, &signal);
      server.stop();
    });
    server.run();
    pthread_kill(waiter.native_handle(), SIGTERM);  // when the server ended by itself
    waiter.join();
  });
}

}  // namespace lightstage::cli
