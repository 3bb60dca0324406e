// lightstage-sim: the simulated physical world of a dome as a process. It
// serves a virtual gpiochip with the rig's lines to the firmware's `sim:`
// backend, records every line change (the firmware's timestamps) and emulates
// the camera's strobe; with --camera it also serves a virtual camera that
// renders the scene lit by the LEDs on during each exposure, and with --dslr
// a stills camera on the trigger (remote-release) line that writes a raw file
// per shot into a folder. Runs until SIGINT or SIGTERM. See docs/sim-gpio.md.
#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/common/socket_link.hpp"
#include "lightstage/common/version.hpp"
#include "lightstage/sim/camera/camera_service.hpp"
#include "lightstage/sim/camera/dslr.hpp"
#include "lightstage/sim/gpio/chip_layout.hpp"
#include "lightstage/sim/gpio/fault.hpp"
#include "lightstage/sim/gpio/gpio_service.hpp"
#include "lightstage/sim/gpio/service_host.hpp"
#include "lightstage/sim/gpio/timeline.hpp"
#include "lightstage/sim/gpio/virtual_chip.hpp"
#include "lightstage/sim/simulate.hpp"

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <pthread.h>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <utility>

namespace {

namespace simgpio = lightstage::sim::gpio;

struct Options {
  std::string rig_path = lightstage::default_rig_path().string();
  std::string listen;
  std::string timeline;
  std::optional<double> strobe_delay_us;
  std::optional<double> strobe_exposure_us;
  bool no_strobe = false;
  std::vector<std::string> faults;
  std::string log_level = "info";
  // The virtual camera.
  std::string camera;
  lightstage::sim::SimulateOptions scene;
  std::string lights = "near";
  std::string noise = "physical";
  std::string response = "identity";
  std::vector<std::string> camera_faults;
  // The DSLR on the remote-release port.
  std::string dslr;
  std::optional<double> dslr_exposure_us, dslr_iso;
  std::string dslr_lag_ms = "40:120", dslr_card_delay_ms = "150:900";
  std::vector<std::string> dslr_drops;
  double dslr_drop_rate = 0;
  double dslr_clock_offset_ms = 0;
  std::string dslr_focus_line;
  int dslr_buffer = lightstage::sim::DslrOptions{}.buffer_shots;
  std::uint64_t dslr_seed = 1;
};

// "MIN:MAX" milliseconds, 0 <= MIN <= MAX, as nanoseconds.
std::pair<std::int64_t, std::int64_t> ms_range(const std::string& flag, const std::string& text) {
  const auto colon = text.find(':');
  auto number = [&](const std::string& part) {
    char* end = nullptr;
    const double value = std::strtod(part.c_str(), &end);
    if (part.empty() || end != part.c_str() + part.size() || !std::isfinite(value)) {
      lightstage::fail("{} '{}': '{}' is not a number of milliseconds (expected MIN:MAX)", flag, text, part);
    }
    return value;
  };
  if (colon == std::string::npos) lightstage::fail("{} '{}': expected MIN:MAX in milliseconds", flag, text);
  const double min = number(text.substr(0, colon)), max = number(text.substr(colon + 1));
  if (min < 0) lightstage::fail("{} '{}': MIN {} is negative", flag, text, min);
  if (min > max) lightstage::fail("{} '{}': MIN {} is above MAX {}", flag, text, min, max);
  return {std::llround(min * 1e6), std::llround(max * 1e6)};
}

// The DSLR's options from its flags; the shutter is the rig's trigger line.
lightstage::sim::DslrOptions dslr_options(const Options& options, const simgpio::ChipLayout& layout) {
  lightstage::sim::DslrOptions o;
  o.folder = options.dslr;
  if (!layout.trigger) lightstage::fail("--dslr: the rig has no trigger line to fire the camera");
  o.shutter_line = layout.display_name(*layout.trigger);
  if (!options.dslr_focus_line.empty()) {
    const auto offset = layout.resolve(options.dslr_focus_line);
    if (!offset) {
      lightstage::fail("--dslr-focus-line '{}': the virtual chip has no such line (a name or an offset)",
                       options.dslr_focus_line);
    }
    if (offset == layout.trigger)
      lightstage::fail("--dslr-focus-line '{}': that is the trigger (shutter) line", options.dslr_focus_line);
    o.focus_line = layout.display_name(*offset);
  }
  if (options.dslr_exposure_us &&
      !(*options.dslr_exposure_us > 0 && std::isfinite(*options.dslr_exposure_us)))
    lightstage::fail("--dslr-exposure-us {}: must be positive", *options.dslr_exposure_us);
  o.exposure_us = options.dslr_exposure_us;
  if (options.dslr_iso && !(*options.dslr_iso > 0 && std::isfinite(*options.dslr_iso)))
    lightstage::fail("--dslr-iso {}: must be positive", *options.dslr_iso);
  o.iso = options.dslr_iso;
  std::tie(o.lag_min_ns, o.lag_max_ns) = ms_range("--dslr-lag-ms", options.dslr_lag_ms);
  std::tie(o.delay_min_ns, o.delay_max_ns) = ms_range("--dslr-card-delay-ms", options.dslr_card_delay_ms);
  for (const auto& drop : options.dslr_drops) {
    char* end = nullptr;
    const unsigned long long n = std::strtoull(drop.c_str(), &end, 10);
    if (drop.empty() || drop[0] == '-' || end != drop.c_str() + drop.size() || n == 0)
      lightstage::fail("--dslr-drop '{}': expected shot numbers N >= 1 (counting from 1), comma-separated",
                       drop);
    o.drop_shots.insert(n);
  }
  if (!(options.dslr_drop_rate >= 0 && options.dslr_drop_rate < 1))
    lightstage::fail("--dslr-drop-rate {}: must be in [0, 1)", options.dslr_drop_rate);
  o.drop_rate = options.dslr_drop_rate;
  if (!std::isfinite(options.dslr_clock_offset_ms))
    lightstage::fail("--dslr-clock-offset-ms {}: must be a number of milliseconds",
                     options.dslr_clock_offset_ms);
  o.clock_offset_ns = std::llround(options.dslr_clock_offset_ms * 1e6);
  if (options.dslr_buffer < 1) lightstage::fail("--dslr-buffer {}: must be at least 1", options.dslr_buffer);
  o.buffer_shots = options.dslr_buffer;
  o.seed = options.dslr_seed;
  o.check();
  return o;
}

// The world the virtual camera sees, and its sensor.
lightstage::sim::SimulateOptions scene_options(Options options) {
  auto& o = options.scene;
  o.light_model = lightstage::sim::parse_light_model(options.lights);
  if (options.noise == "none") {
    o.sensor.noise = lightstage::sim::NoiseModel::kNone;
  } else if (options.noise != "physical") {
    lightstage::fail("--noise: '{}' is not none or physical", options.noise);
  }
  o.sensor.response = lightstage::sim::ResponseCurve::parse(options.response);
  o.check();
  return o;
}

simgpio::VirtualChipOptions chip_options(const lightstage::Rig& rig, const Options& options) {
  simgpio::VirtualChipOptions chip = simgpio::chip_options_for(rig);
  if (options.no_strobe) chip.strobe = false;
  if (options.strobe_delay_us) chip.strobe_delay_ns = std::llround(*options.strobe_delay_us * 1000.0);
  if (options.strobe_exposure_us)
    chip.strobe_exposure_ns = std::llround(*options.strobe_exposure_us * 1000.0);
  chip.check();
  return chip;
}

int serve(const Options& options, const sigset_t& stop_signals) {
  const lightstage::Rig rig = lightstage::load_rig(options.rig_path);
  const auto chip_opts = chip_options(rig, options);
  auto chip = std::make_shared<simgpio::VirtualChip>(simgpio::layout_from_rig(rig), chip_opts);
  if (!options.timeline.empty()) {
    chip->add_timeline_sink(std::make_shared<simgpio::JsonLinesTimelineFile>(options.timeline));
  }
  auto gpio = std::make_shared<simgpio::GpioService>(chip);
  for (const auto& fault : options.faults) gpio->inject(simgpio::parse_fault(fault));

  lightstage::sim::ServiceHost host;
  auto listener = lightstage::listen_socket_link(options.listen);
  const std::string uri = lightstage::bound_uri(*listener);
  host.add(std::move(listener), gpio);
  std::shared_ptr<lightstage::sim::CameraService> camera;
  std::shared_ptr<lightstage::sim::SimulatedDslr> dslr;
  std::string camera_uri;
  // The world both cameras see, rendered by whichever asks.
  const bool renders = !options.camera.empty() || !options.dslr.empty();
  const auto scene = renders ? scene_options(options) : options.scene;
  std::shared_ptr<const lightstage::sim::World> world;
  if (renders) world = std::make_shared<const lightstage::sim::World>(rig, scene);
  if (!options.camera.empty()) {
    lightstage::sim::CameraServiceOptions camera_options;
    if (chip->layout().trigger)
      camera_options.trigger_line = chip->layout().display_name(*chip->layout().trigger);
    camera_options.trigger_delay_ns = chip_opts.strobe_delay_ns;
    camera_options.seed = scene.seed;
    for (const auto& fault : options.camera_faults) {
      const std::string prefix = "drop-frame:";
      std::uint64_t n = 0;
      if (!fault.starts_with(prefix) ||
          (n = std::strtoull(fault.c_str() + prefix.size(), nullptr, 10)) == 0) {
        lightstage::fail("--camera-fault '{}': expected drop-frame:N with N >= 1", fault);
      }
      camera_options.drop_frames.insert(n);
    }
    // The emulated strobe follows the camera's exposure, as a real camera's output does.
    camera_options.on_exposure_change = [chip](std::int64_t ns) { chip->set_strobe_exposure_ns(ns); };
    camera = std::make_shared<lightstage::sim::CameraService>(world, scene.sensor, camera_options);
    chip->add_timeline_sink(camera->tracker());
    auto camera_listener = lightstage::listen_socket_link(options.camera);
    camera_uri = lightstage::bound_uri(*camera_listener);
    host.add(std::move(camera_listener), camera);
  }
  // Beside the virtual camera, not instead of it: both only watch the trigger
  // edges, and the `sim:` camera renders only while a client streams from it.
  if (!options.dslr.empty()) {
    dslr = std::make_shared<lightstage::sim::SimulatedDslr>(world, scene.sensor,
                                                            dslr_options(options, chip->layout()));
    chip->add_timeline_sink(dslr);
  }

  auto log = lightstage::logger("sim");
  log->info("rig '{}': {} lines, {} LEDs, {} chain(s); strobe {}", rig.name, chip->layout().lines.size(),
            rig.leds.size(), rig.chains.size(),
            chip_opts.strobe && chip->layout().strobe
                ? fmt::format("on (delay {} us, exposure {} us)", chip_opts.strobe_delay_ns / 1000.0,
                              chip_opts.strobe_exposure_ns / 1000.0)
                : std::string("off"));
  if (dslr) {
    const auto black = dslr->black_levels();
    log->info(
        "dslr: shutter on {}, files {}... into {}; exposure {} us, ISO {}, black {}/{}/{}/{} DN, white {} DN",
        chip->layout().display_name(*chip->layout().trigger),
        lightstage::sim::SimulatedDslr::file_name(dslr->first_file_number()), options.dslr,
        dslr->exposure_us(), dslr->iso(), black[0], black[1], black[2], black[3], dslr->white_level());
  }
  if (camera) fmt::print("lightstage-sim: camera on {}\n", camera_uri);
  if (dslr) fmt::print("lightstage-sim: dslr writes into {}\n", options.dslr);
  fmt::print("lightstage-sim: listening on {}\n", uri);
  std::fflush(stdout);

  int signal = 0;
  sigwait(&stop_signals, &signal);
  log->info("{}: stopping", signal == SIGINT ? "SIGINT" : "SIGTERM");
  host.stop();
  const auto stats = chip->stats();
  if (camera) log->info("camera: {} frame(s) delivered", camera->frames_sent());
  if (dslr) {
    const auto s = dslr->stats();
    log->info(
        "dslr: {} press(es): {} shot(s) taken, {} on the card, {} lost, {} not written; ignored: {} busy, {} "
        "buffer full, {} without focus",
        s.presses, s.taken, s.written, s.dropped, s.failed, s.ignored_busy, s.ignored_buffer,
        s.ignored_focus);
  }
  log->info("served {} trigger(s): {} strobe(s), {} lost to faults, {} ignored during an exposure",
            stats.triggers, stats.strobes, stats.strobes_lost, stats.triggers_ignored);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "lightstage-sim: the simulated dome: a virtual gpiochip with the rig's lines, a timeline of every "
      "line change and an emulated camera strobe."};
  Options options;
  bool version = false;
  app.add_option("--rig", options.rig_path, "rig description (YAML)")->capture_default_str();
  app.add_option("--listen", options.listen,
                 "where to serve the virtual gpiochip: unix:PATH or tcp:HOST:PORT");
  app.add_option("--timeline", options.timeline, "append every line change to FILE as JSON lines");
  app.add_option("--strobe-delay-us", options.strobe_delay_us,
                 "strobe active this long after the trigger's active edge (default 100)");
  app.add_option("--strobe-exposure-us", options.strobe_exposure_us,
                 "strobe active this long (default: the rig camera's exposure_us)");
  app.add_flag("--no-strobe", options.no_strobe, "do not emulate the camera's strobe");
  app.add_option("--fault", options.faults,
                 "inject a fault (repeatable): lose-strobe:N, stuck:LINE, drop-connection:N");
  app.add_option("--log-level", options.log_level, "trace, debug, info, warn, error, off")
      ->capture_default_str();
  app.add_option("--camera", options.camera,
                 "also serve a virtual camera here (unix:PATH); the host opens it as sim:PATH");
  app.add_option("--scene", options.scene.scene, "camera: scene preset or scene YAML file")
      ->capture_default_str();
  app.add_option("--material", options.scene.material, "camera: material preset (default: the scene's)");
  app.add_option("--lights", options.lights, "camera: LEDs as near point lights or distant")
      ->capture_default_str()
      ->check(CLI::IsMember({"near", "distant"}));
  app.add_option("--width", options.scene.width, "camera: image width (default: the rig camera's)");
  app.add_option("--height", options.scene.height, "camera: image height (default: the rig camera's)");
  app.add_option("--noise", options.noise, "camera: sensor noise, none or physical")->capture_default_str();
  app.add_option("--response", options.response,
                 "camera: response curve: identity, gamma:2.2, srgb, s-curve:2")
      ->capture_default_str();
  app.add_option("--black-level", options.scene.sensor.black_level,
                 "camera: black level, DN (dslr: 512 when 0)");
  app.add_option("--seed", options.scene.seed, "camera: noise seed")->capture_default_str();
  app.add_option("--camera-fault", options.camera_faults,
                 "camera: inject a fault (repeatable): drop-frame:N loses the N-th frame");
  auto* dslr =
      app.add_option("--dslr", options.dslr,
                     "also fire a simulated DSLR on the trigger (remote-release) line, writing "
                     "IMG_NNNN.DNG into DIR (created if missing; numbering continues after the files "
                     "there)")
          ->type_name("DIR");
  app.add_option("--dslr-exposure-us", options.dslr_exposure_us,
                 "dslr: exposure time (default: the rig camera's exposure_us)")
      ->needs(dslr);
  app.add_option("--dslr-iso", options.dslr_iso, "dslr: ISO, 100 x gain (default: 100 x the camera's gain)")
      ->needs(dslr);
  app.add_option("--dslr-lag-ms", options.dslr_lag_ms, "dslr: shutter lag MIN:MAX, drawn uniformly")
      ->type_name("MIN:MAX")
      ->capture_default_str()
      ->needs(dslr);
  app.add_option("--dslr-card-delay-ms", options.dslr_card_delay_ms,
                 "dslr: end of exposure to file on the card MIN:MAX, drawn uniformly (files stay in order)")
      ->type_name("MIN:MAX")
      ->capture_default_str()
      ->needs(dslr);
  app.add_option("--dslr-drop", options.dslr_drops,
                 "dslr: shots whose file is lost, N[,N...] counting from 1 (repeatable)")
      ->type_name("N[,N...]")
      ->delimiter(',')
      ->needs(dslr);
  app.add_option("--dslr-drop-rate", options.dslr_drop_rate,
                 "dslr: chance in [0, 1) that a shot's file is lost")
      ->capture_default_str()
      ->needs(dslr);
  app.add_option("--dslr-clock-offset-ms", options.dslr_clock_offset_ms,
                 "dslr: the camera clock's error, added to the EXIF time")
      ->capture_default_str()
      ->needs(dslr);
  app.add_option("--dslr-focus-line", options.dslr_focus_line,
                 "dslr: the half-press line (name or offset); the camera then ignores a shutter without it")
      ->type_name("NAME")
      ->needs(dslr);
  app.add_option("--dslr-buffer", options.dslr_buffer,
                 "dslr: shots exposed but not yet on the card at most; a press beyond is ignored")
      ->capture_default_str()
      ->needs(dslr);
  app.add_option("--dslr-seed", options.dslr_seed, "dslr: seed of the lag, delay, drop and noise draws")
      ->capture_default_str()
      ->needs(dslr);
  app.add_flag("--version", version, "print the version");
  CLI11_PARSE(app, argc, argv);
  if (version) {
    fmt::print("lightstage-sim {}\n", lightstage::kVersion);
    return 0;
  }
  if (options.listen.empty()) {
    std::cerr << "lightstage-sim: --listen is required (e.g. --listen unix:/tmp/lightstage-sim.sock)\n";
    return 2;
  }
  // SIGINT/SIGTERM are taken by sigwait() in serve(): block them before any
  // thread starts so every thread inherits the mask. A vanished peer must not
  // kill the sim either.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
  try {
    lightstage::set_log_level(options.log_level);
    return serve(options, stop_signals);
  } catch (const lightstage::Error& e) {
    std::cerr << "lightstage-sim: " << e.what() << "\n";
    return 1;
  }
}
