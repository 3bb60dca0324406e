#include "lightstage/host/capture/capture_session.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/capture/capture_plan.hpp"
#include "lightstage/host/capture/capture_runner.hpp"
#include "lightstage/host/capture/response_curve.hpp"
#include "lightstage/host/capture/stack_writer.hpp"
#include "lightstage/host/io/output_folder.hpp"
#include "lightstage/host/progress.hpp"
#include "util/elapsed.hpp"

#include <fmt/format.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <optional>

namespace fs = std::filesystem;

namespace lightstage {
namespace {

using SteadyClock = std::chrono::steady_clock;

// The camera is stopped however the capture ends.
struct StopCamera {
  CaptureRunner& runner;
  ~StopCamera() {
    try {
      runner.stop();
    } catch (const std::exception&) {
    }
  }
};

CaptureReport run_capture(const Rig& rig, ControllerClient& controller, camera::Camera& cam,
                          const CaptureOptions& options, CaptureRunner& runner,
                          const InverseResponse* response) {
  const SteadyClock::time_point started = SteadyClock::now();
  const std::vector<int> led_ids = plan_led_ids(rig, options.led_ids);
  if (!options.resume)
    io::require_empty_folder(options.out, "--out",
                             "use --resume to complete an interrupted capture, or another --out");
  fs::create_directories(options.out);
  CaptureStackWriter writer(rig, options.out, response);
  PreviousPlan previous;
  if (options.resume) previous = writer.resume(led_ids, options);

  runner.start();
  const StopCamera stop_camera{runner};

  // Exposures: fixed, automatic, or as planned before an interruption.
  std::map<int, double> exposure_of = previous.exposure_us;
  std::vector<int> unplanned;
  for (const int id : led_ids) {
    if (!exposure_of.count(id)) unplanned.push_back(id);
  }
  if (!unplanned.empty()) {
    if (options.exposure_us) {
      for (const int id : unplanned) exposure_of[id] = *options.exposure_us;
    } else {
      const auto preview = [&](const std::vector<int>& ids, double exposure_us) {
        std::vector<Shot> shots;
        for (const int id : ids) shots.push_back({id, exposure_us});
        Batch batch = runner.run_batch(shots);
        std::vector<camera::Frame> frames;
        for (auto& [i, taken] : batch.taken) frames.push_back(std::move(taken.frame));
        return frames;
      };
      for (const auto& [id, e] : auto_exposures(rig, unplanned, cam.control_info(), options, preview))
        exposure_of[id] = e;
    }
  }
  std::map<int, std::vector<double>> bracket_of = previous.bracket_exposure_us;
  const bool hdr = !options.bracket_stops.empty();
  if (hdr) {
    for (const int id : led_ids) {
      if (!bracket_of.count(id)) {
        bracket_of[id] =
            bracket_exposures(rig.led(id), exposure_of.at(id), options.bracket_stops, cam.control_info(),
                              lit_overhead_us(rig.trigger, options.settle_us));
      }
    }
  } else {
    bracket_of.clear();
  }
  const CapturePlan plan =
      make_plan(led_ids, exposure_of, bracket_of, options.bracket_stops, options.dark_frames);
  check_on_time(plan, runner.on_time_limits(rig), lit_overhead_us(rig.trigger, options.settle_us));

  const camera::CameraInfo camera_info = cam.info();
  writer.set_plan(plan,
                  {runner.gain(), runner.closed_loop(), runner.hardware_trigger(), camera_info,
                   controller.info().firmware_version(), controller.info().rig_name(), options.exposure_us});
  writer.write_index(false);

  CaptureReport report;
  if (plan.dark_frames > 0) {
    for (const std::size_t e : plan.taken_exposures()) {
      if (writer.has_dark(e)) continue;  // resumed: already taken
      const Batch batch = runner.run_batch(
          std::vector<Shot>(static_cast<std::size_t>(plan.dark_frames), Shot{-1, plan.exposures_us[e]}));
      std::vector<cv::Mat> images;
      for (const auto& [i, taken] : batch.taken) images.push_back(taken.frame.image);
      writer.add_dark(e, images);
      report.dark_frames += images.size();
    }
  }
  writer.write_index(false);

  Progress progress("capture", plan.frames.size(), "frames", options.mode);
  progress.advance(writer.frame_count());
  // Frames are written as they come, the index after each: the folder stays a
  // loadable stack of every frame on disk.
  runner.take_frames(plan, writer.done(), [&](std::size_t frame, std::vector<Take>& takes) {
    if (hdr) {
      writer.add_hdr_frame(frame, takes);
      report.bracket_frames += takes.size();
    } else {
      writer.add_frame(frame, takes.front());
    }
    ++report.taken_now;
    writer.write_index(false);
    progress.advance();
    if (options.on_progress)
      options.on_progress(
          {writer.frame_count(), plan.frames.size(), plan.frames[frame].led_id, report.taken_now});
  });
  progress.finish();
  writer.write_index(true);
  report.frames = writer.frame_count();
  report.retakes = runner.stats().retakes;
  report.duplicates = runner.stats().duplicates;
  report.camera_wait_seconds = runner.stats().camera_wait_seconds;
  report.seconds = seconds_since(started);
  report.message = fmt::format(
      "{} frames in {:.1f} s ({} taken now, {} retaken, {} duplicates dropped, {} dark{})", report.frames,
      report.seconds, report.taken_now, report.retakes, report.duplicates, report.dark_frames,
      hdr ? fmt::format(", HDR from {} bracket frames", report.bracket_frames) : std::string());
  return report;
}

}  // namespace

nlohmann::json CaptureReport::to_json() const {
  return {{"frames", frames},           {"taken_now", taken_now},
          {"retakes", retakes},         {"duplicates", duplicates},
          {"dark_frames", dark_frames}, {"bracket_frames", bracket_frames},
          {"seconds", seconds},         {"camera_wait_seconds", camera_wait_seconds},
          {"message", message}};
}

CaptureReport capture_stack(const Rig& rig, ControllerClient& controller, camera::Camera& cam,
                            const CaptureOptions& options) {
  options.check();
  CaptureRunner runner(controller, cam, options, rig.trigger);
  std::optional<InverseResponse> response;
  if (!options.response.empty()) response = InverseResponse::load(options.response);
  // What is kept, and how to go on: resumed from the page after a stop, with --resume after a failure.
  const auto stopped = [&](const std::exception& e) {
    return CaptureStopped(fmt::format("{}; the frames taken so far are kept in {} (resume completes it)",
                                      e.what(), options.out.string()));
  };
  const auto failed = [&](const std::exception& e) {
    return Error(fmt::format("{}; the frames taken so far are kept in {} (complete it with --resume)",
                             e.what(), options.out.string()));
  };
  try {
    return run_capture(rig, controller, cam, options, runner, response ? &*response : nullptr);
  } catch (const InputError&) {
    throw;
  } catch (const CaptureStopped& e) {
    throw stopped(e);
  } catch (const BatchAborted& e) {
    // Cut short because a stop or a halt was asked for (darks, exposure metering): a stop, not a failure.
    const bool asked = (options.halt_requested && options.halt_requested()) ||
                       (options.stop_requested && options.stop_requested());
    if (asked) throw stopped(e);
    throw failed(e);
  } catch (const Error& e) {
    throw failed(e);  // the controller, the camera or the link failed
  }
}

std::vector<cv::Mat> capture_bracket(const Rig& rig, ControllerClient& controller, camera::Camera& cam,
                                     int led_id, const std::vector<double>& exposures_us,
                                     const CaptureOptions& options) {
  if (exposures_us.empty()) fail("bracket: no exposures given");
  for (const double e : exposures_us) {
    if (!(e > 0)) fail("bracket: exposure {} us is not positive", e);
  }
  CaptureRunner runner(controller, cam, options, rig.trigger);
  rig.led(led_id);  // throws for an unknown id
  runner.start();
  std::vector<cv::Mat> images;
  for (const double e : exposures_us) {
    Batch batch = runner.run_batch({Shot{led_id, e}});
    images.push_back(batch.taken.at(0).frame.image);
  }
  runner.stop();
  return images;
}

}  // namespace lightstage
