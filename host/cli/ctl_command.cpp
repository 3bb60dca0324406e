// `lightstage ctl`: talk to a dome controller directly, for bringing up a
// dome: what it is, light LEDs by hand, run every LED once as a capture would.
#include "commands.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/controller/controller_client.hpp"
#include "lightstage/host/controller/led_hold.hpp"
#include "lightstage/host/controller/sequences.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <memory>

namespace lightstage::cli {
namespace {

struct CtlArgs {
  std::string controller = "unix:/run/lightstage/domed.sock";
  std::uint32_t watchdog_ms = 0;
  bool json = false;
  // leds
  std::vector<std::uint32_t> on;
  float level = 1.0f;
  std::uint32_t hold_ms = 1000;
  // run-test-sequence
  OneLedPerStepOptions sequence;
  std::string loop = "auto";
};

std::unique_ptr<ControllerClient> connect(const CtlArgs& args) {
  ControllerClientOptions options;
  options.client_name = "lightstage ctl";
  options.watchdog_timeout_ms = args.watchdog_ms;
  return connect_controller(args.controller, options);
}

void print_info(const proto::Info& info, bool json) {
  const auto& caps = info.capabilities();
  if (json) {
    nlohmann::json j = {{"protocol_version", info.protocol_version()},
                        {"firmware_version", info.firmware_version()},
                        {"rig", info.rig_name()},
                        {"led_count", info.led_count()},
                        {"gpio", info.gpio_uri()},
                        {"strobe_input", caps.strobe_input()},
                        {"dimming", caps.dimming()},
                        {"realtime", caps.realtime()},
                        {"max_sequence_steps", caps.max_sequence_steps()},
                        {"watchdog_timeout_ms", caps.watchdog_timeout_ms()}};
    fmt::print("{}\n", j.dump(2));
    return;
  }
  fmt::print("controller: {} (protocol {}), rig '{}', {} LEDs, GPIO {}\n", info.firmware_version(),
             info.protocol_version(), info.rig_name(), info.led_count(), info.gpio_uri());
  fmt::print("capabilities: strobe input {}, dimming {}, realtime {}, up to {} steps, watchdog {} ms\n",
             caps.strobe_input() ? "yes" : "no", caps.dimming() ? "yes" : "no",
             caps.realtime() ? "yes" : "no", caps.max_sequence_steps(), caps.watchdog_timeout_ms());
}

void run_test_sequence(const CtlArgs& args) {
  auto client = connect(args);
  OneLedPerStepOptions options = args.sequence;
  if (args.loop == "closed") {
    if (!client->info().capabilities().strobe_input()) {
      fail("--loop closed: the controller's rig has no strobe input");
    }
    options.closed_loop = true;
  } else {
    options.closed_loop = args.loop == "auto" && client->info().capabilities().strobe_input();
  }
  const proto::Sequence sequence = one_led_per_step(led_ids(client->info()), options, 1);
  if (!args.json) {
    fmt::print("running {} steps ({} loop) on '{}'\n", sequence.steps_size(),
               options.closed_loop ? "closed" : "open", client->info().rig_name());
  }
  nlohmann::json steps = nlohmann::json::array();
  const SequenceRun run = client->run_sequence(sequence, [&](const proto::StepEvent& e) {
    const double exposure_ms = e.strobe_fall_ns() && e.strobe_rise_ns()
                                   ? (e.strobe_fall_ns() - e.strobe_rise_ns()) / 1e6
                                   : (e.leds_off_ns() - e.trigger_ns()) / 1e6;
    if (args.json) {
      steps.push_back({{"step", e.step()},
                       {"leds", std::vector<std::uint32_t>(e.led_ids().begin(), e.led_ids().end())},
                       {"leds_on_ns", e.leds_on_ns()},
                       {"trigger_ns", e.trigger_ns()},
                       {"strobe_rise_ns", e.strobe_rise_ns()},
                       {"strobe_fall_ns", e.strobe_fall_ns()},
                       {"leds_off_ns", e.leds_off_ns()},
                       {"lateness_ns", e.lateness_ns()},
                       {"outcome", proto::Outcome_Name(e.outcome())}});
    } else {
      fmt::print("step {:3}  LED {:4}  exposure {:7.3f} ms  late {:7.3f} ms  {}\n", e.step(),
                 e.led_ids_size() ? std::to_string(e.led_ids(0)) : "-", exposure_ms, e.lateness_ns() / 1e6,
                 proto::Outcome_Name(e.outcome()));
    }
  });
  const LatenessStats lateness = lateness_stats(run.steps);
  if (args.json) {
    fmt::print(
        "{}\n",
        nlohmann::json{{"outcome", proto::Outcome_Name(run.done.outcome())},
                       {"detail", run.done.detail()},
                       {"steps_run", run.done.steps_run()},
                       {"lateness_ns",
                        {{"median", lateness.median_ns}, {"p99", lateness.p99_ns}, {"max", lateness.max_ns}}},
                       {"steps", steps}}
            .dump(2));
  } else {
    fmt::print("{}: {} of {} steps; lateness median {:.3f} ms, p99 {:.3f} ms, max {:.3f} ms{}\n",
               proto::Outcome_Name(run.done.outcome()), run.done.steps_run(), sequence.steps_size(),
               lateness.median_ns / 1e6, lateness.p99_ns / 1e6, lateness.max_ns / 1e6,
               run.done.detail().empty() ? "" : " — " + run.done.detail());
  }
  if (!run.ok())
    throw Error(fmt::format("test sequence ended {}: {}", proto::Outcome_Name(run.done.outcome()),
                            run.done.detail()));
}

// Lights the LEDs for --hold-ms; a fault on the way is printed and fails the command.
void hold_leds(const CtlArgs& args) {
  std::vector<std::pair<std::uint32_t, float>> levels;
  for (const std::uint32_t id : args.on) levels.emplace_back(id, args.level);
  const LedHold hold = lightstage::hold_leds(*connect(args), levels, std::chrono::milliseconds(args.hold_ms));
  if (args.json) {
    const nlohmann::json fault = hold.faulted ? nlohmann::json(hold.fault) : nlohmann::json();
    fmt::print("{}\n",
               nlohmann::json{
                   {"leds", args.on}, {"hold_ms", args.hold_ms}, {"held_ms", hold.held_ms}, {"fault", fault}}
                   .dump(2));
  }
  if (hold.faulted) {
    throw Error(fmt::format("the controller switched the LEDs off after {} ms of the {} ms asked: {}",
                            hold.held_ms, args.hold_ms, hold.fault));
  }
}

}  // namespace

void add_ctl(CLI::App& app) {
  auto args = std::make_shared<CtlArgs>();
  CLI::App* ctl =
      app.add_subcommand("ctl",
                         "Talk to a dome controller (lightstage-domed) directly: bring-up and diagnostics.\n"
                         "Connects to --controller (docs/protocol.md) and runs one subcommand: info, status, "
                         "abort, leds (light LEDs by hand) or run-test-sequence (every LED once, with "
                         "triggers, and the timing). Prints what the controller answered (--json: as JSON); "
                         "exits non-zero when it reports a fault.\n"
                         "Example: lightstage ctl --controller tcp:dome.local:7700 run-test-sequence");
  ctl->require_subcommand(1);
  ctl->add_option("--controller", args->controller,
                  "controller URI: tcp:HOST:PORT, unix:PATH, serial:DEV, usb:VID:PID")
      ->capture_default_str();
  ctl->add_option("--watchdog-ms", args->watchdog_ms,
                  "heartbeat timeout to ask for (0 = the controller's default)");
  ctl->add_flag("--json", args->json, "machine-readable output");

  ctl->add_subcommand("info", "Print the controller's firmware version, rig, LEDs and capabilities.")
      ->callback([args] { print_info(connect(*args)->info(), args->json); });

  ctl->add_subcommand("status",
                      "Print what the controller is doing: state, sequence and step, LEDs on, last fault.")
      ->callback([args] {
        const proto::Status s = connect(*args)->status();
        std::vector<std::uint32_t> on(s.leds_on().begin(), s.leds_on().end());
        if (args->json) {
          fmt::print("{}\n", nlohmann::json{{"state", proto::Status::State_Name(s.state())},
                                            {"sequence_id", s.sequence_id()},
                                            {"step", s.step()},
                                            {"leds_on", on},
                                            {"last_fault", s.last_fault()}}
                                 .dump(2));
        } else {
          fmt::print("state {}, sequence {}, step {}, {} LED(s) on{}\n", proto::Status::State_Name(s.state()),
                     s.sequence_id(), s.step(), on.size(),
                     s.last_fault().empty() ? "" : ", last fault: " + s.last_fault());
        }
      });

  ctl->add_subcommand("abort", "Abort a running sequence and darken the dome.")->callback([args] {
    connect(*args)->abort();
  });

  CLI::App* leds = ctl->add_subcommand(
      "leds",
      "Light the given LEDs (all others dark) for --hold-ms, then darken the dome. When the controller\n"
      "switches them off sooner (an LED's on-time limit), prints its fault and exits non-zero.\n"
      "Example: lightstage ctl --controller unix:/tmp/domed.sock leds --on 3,17 --hold-ms 2000");
  leds->add_option("--on", args->on, "LED ids to light (none: all dark)")->delimiter(',');
  leds->add_option("--level", args->level, "level 0..1 (drivers without dimming accept 1 only)")
      ->capture_default_str()
      ->check(CLI::Range(0.0f, 1.0f));
  leds->add_option("--hold-ms", args->hold_ms, "how long to keep them lit")->capture_default_str();
  leds->callback([args] { hold_leds(*args); });

  CLI::App* test = ctl->add_subcommand(
      "run-test-sequence",
      "Light every LED of the rig once in turn, with a camera trigger, as a capture would; prints the\n"
      "outcome, the steps run and the timing lateness (median, p99, max; --json adds every step).\n"
      "Example: lightstage ctl --controller unix:/tmp/domed.sock run-test-sequence --loop open");
  test->add_option("--settle-us", args->sequence.settle_us, "LED on to trigger")->capture_default_str();
  test->add_option("--exposure-us", args->sequence.exposure_us, "open loop: LED time after the trigger")
      ->capture_default_str();
  test->add_option("--gap-us", args->sequence.gap_us, "dark time between steps")->capture_default_str();
  test->add_option("--strobe-timeout-us", args->sequence.strobe_timeout_us,
                   "closed loop: longest wait for the strobe")
      ->capture_default_str();
  test->add_option("--loop", args->loop,
                   "open, closed (wait for the camera strobe) or auto (closed if the rig has one)")
      ->capture_default_str()
      ->check(CLI::IsMember({"open", "closed", "auto"}));
  test->callback([args] { run_test_sequence(*args); });
}

}  // namespace lightstage::cli
