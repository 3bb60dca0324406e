#include "lightstage/station/station.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/rig_fingerprint.hpp"
#include "lightstage/host/calibration/calibrate_lights.hpp"
#include "lightstage/host/calibration/calibration_images.hpp"
#include "lightstage/host/calibration/calibration_output.hpp"
#include "lightstage/host/capture/capture_runner.hpp"
#include "lightstage/host/capture/capture_session.hpp"
#include "lightstage/host/controller/sequences.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/report/report.hpp"
#include "lightstage/pipeline/integrate_folder.hpp"
#include "lightstage/pipeline/rti_exchange.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/pipeline/solve_methods.hpp"
#include "lightstage/station/operator_access.hpp"
#include "lightstage/station/preview_figures.hpp"

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>

namespace lightstage::station {

namespace fs = std::filesystem;

namespace {

nlohmann::json read_json_or_null(const fs::path& file) {
  std::ifstream in(file);
  if (!in) return nullptr;
  return nlohmann::json::parse(in, nullptr, false);  // discarded (not thrown) when malformed
}

// Written beside, then renamed: never half a file.
void write_json_atomically(const fs::path& file, const nlohmann::json& value) {
  fs::create_directories(file.parent_path());
  const fs::path partial = file.string() + ".partial";
  {
    std::ofstream out(partial);
    out << value.dump(2) << "\n";
    if (!out) throw Error(fmt::format("cannot write {}", partial.string()));
  }
  fs::rename(partial, file);
}

nlohmann::json controller_json(const proto::Info& info, const proto::Status& status) {
  return {{"firmware", info.firmware_version()},
          {"rig", info.rig_name()},
          {"watchdog_ms", info.capabilities().watchdog_timeout_ms()},
          {"state", proto::Status::State_Name(status.state())},
          {"leds_on", std::vector<std::uint32_t>(status.leds_on().begin(), status.leds_on().end())},
          {"last_fault", status.last_fault()}};
}

std::string file_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Whether the stack's mask.png is still the outline this station drew (its
// marker holds the mask's hash): anything else there is the operator's, not ours to replace.
bool drawn_here(const fs::path& stack, const fs::path& marker) {
  // An outline drawn just before a crash: its marker was written, its mask not yet renamed into place.
  const fs::path drawing = stack / ".mask-drawn.png";
  if (fs::exists(drawing)) {
    const nlohmann::json marked = read_json_or_null(marker);
    if (marked.is_object() && marked.value("mask_hash", "") == content_hash(file_bytes(drawing)))
      fs::rename(drawing, stack / "mask.png");
    else
      fs::remove(drawing);  // written before its marker: never in use
  }
  const nlohmann::json drawn = read_json_or_null(marker);
  return drawn.is_object() && drawn.contains("mask_hash") && fs::exists(stack / "mask.png") &&
         drawn["mask_hash"] == content_hash(file_bytes(stack / "mask.png"));
}

}  // namespace

Station::Station(StationOptions options) : options_(std::move(options)), rig_(load_rig(options_.rig)) {
  for (const char* kind : {"stacks", "calibrations", "results", "surfaces", "exports", ".station"})
    fs::create_directories(options_.data / kind);
  if (options_.simulated) {
    SimulatedBenchOptions bench = *options_.simulated;
    bench.rig = options_.rig;
    if (bench.log_dir.empty()) bench.log_dir = options_.data / ".station" / "dome";
    bench_ = std::make_unique<SimulatedBench>(bench);
  }
  // Connected at once, so a wrong URI shows when the page first loads; not fatal: the page says why.
  const std::lock_guard lock(dome_mutex_);
  try {
    may_reconnect();
    dome();
  } catch (const std::exception& e) {
    drop_dome(e.what());
  }
}

Station::~Station() {
  bool sequence = false;
  {
    const std::lock_guard lock(job_mutex_);
    if (job_ && job_->running() && job_->stoppable()) {
      job_->request_stop();
      sequence = job_->kind() == "test-sequence";
    }
  }
  if (sequence) abort_sequence();  // not the whole walk over the dome first
  wait_job();
  try {
    if (const auto connection = connected()) connection->controller->all_off();
  } catch (const std::exception& e) {
    logger("station")->warn("could not darken the dome on the way out (its watchdog will): {}", e.what());
  }
}

std::shared_ptr<pipeline::DomeConnection> Station::connected() const {
  const std::lock_guard lock(link_mutex_);
  return dome_;
}

std::shared_ptr<pipeline::DomeConnection> Station::dome() {
  if (auto connection = connected()) return connection;
  const std::string controller = bench_ ? bench_->controller_uri() : options_.controller_uri;
  const std::string camera = bench_ ? bench_->camera_uri() : options_.camera_uri;
  auto connection =
      std::make_shared<pipeline::DomeConnection>(pipeline::connect_dome(options_.rig, controller, camera));
  {
    const std::lock_guard lock(link_mutex_);
    dome_ = connection;
  }
  const std::lock_guard lock(state_mutex_);
  dome_error_.clear();
  return connection;
}

// A dome that does not answer takes seconds to give up on: the status polls
// of every page try again at most every few seconds, not each time.
bool Station::may_reconnect() {
  const auto now = std::chrono::steady_clock::now();
  if (now - last_connect_attempt_ < std::chrono::seconds(5)) return false;
  last_connect_attempt_ = now;
  return true;
}

void Station::abort_sequence() {
  try {
    if (const auto connection = connected()) connection->controller->abort();
  } catch (const ControllerError&) {
    // Refused: no sequence runs.
  } catch (const std::exception& e) {
    // The link is gone: with no heartbeats the controller's watchdog darkens the dome.
    logger("station")->warn("could not abort the controller's sequence: {}", e.what());
    drop_dome(e.what());
  }
}

void Station::drop_dome(const std::string& why) {
  std::shared_ptr<pipeline::DomeConnection> dropped;
  {
    const std::lock_guard lock(link_mutex_);
    dropped = std::move(dome_);
  }
  // Its threads end here, outside the lock. With its heartbeats gone, the
  // controller's watchdog darkens whatever it had lit.
  dropped.reset();
  const std::lock_guard lock(state_mutex_);
  dome_error_ = why;
  controller_ = nullptr;
  lit_.clear();
  lit_by_hand_ = false;
}

void Station::set_lit(std::vector<std::pair<std::uint32_t, float>> lit, bool by_hand) {
  const std::lock_guard lock(state_mutex_);
  lit_ = std::move(lit);
  lit_by_hand_ = by_hand && !lit_.empty();
}

bool Station::lit_by_hand() const {
  const std::lock_guard lock(state_mutex_);
  return lit_by_hand_;
}

nlohmann::json Station::status() {
  // The controller is asked only when no job talks to it; otherwise its last answer stands.
  if (std::unique_lock lock(dome_mutex_, std::try_to_lock);
      lock.owns_lock() && (connected() || may_reconnect())) {
    try {
      const auto connection = dome();
      const proto::Status status = connection->controller->status();
      const std::lock_guard state(state_mutex_);
      controller_ = controller_json(connection->controller->info(), status);
    } catch (const std::exception& e) {
      drop_dome(e.what());
    }
  }
  nlohmann::json j = {{"rig", {{"name", rig_.name}, {"leds", rig_.leds.size()}}},
                      {"data", options_.data.string()}};
  {
    const std::lock_guard lock(state_mutex_);
    nlohmann::json lit = nlohmann::json::array();
    for (const auto& [id, level] : lit_) lit.push_back({{"id", id}, {"level", level}});
    j["dome"] = {{"connected", controller_ != nullptr && dome_error_.empty()},
                 {"error", dome_error_},
                 {"controller", controller_},
                 {"lit", lit},
                 {"lit_by_hand", lit_by_hand_}};
  }
  j["job"] = job_json();
  j["simulated"] = bench_ ? bench_->to_json() : nlohmann::json(nullptr);
  return j;
}

nlohmann::json Station::rig_json() const {
  nlohmann::json leds = nlohmann::json::array();
  for (const Led& led : rig_.leds) {
    const Vec3 d = rig_.light_direction(led);
    leds.push_back({{"id", led.id},
                    {"direction", {d.x(), d.y(), d.z()}},
                    {"colour", led.colour},
                    {"max_on_us", led.limits.max_on_us}});
  }
  return {{"name", rig_.name},
          {"camera", {{"width", rig_.camera.width}, {"height", rig_.camera.height}}},
          {"leds", leds}};
}

std::vector<std::string> Station::methods() const { return pipeline::solve_method_names(); }

fs::path Station::folder(const char* kind, const std::string& name) const {
  return options_.data / kind / name;
}

nlohmann::json Station::data_json() const {
  const auto names = [&](const char* kind) {
    std::vector<std::string> list;
    for (const auto& entry : fs::directory_iterator(options_.data / kind)) {
      if (entry.is_directory() && entry.path().filename().string().front() != '.')
        list.push_back(entry.path().filename().string());
    }
    std::sort(list.begin(), list.end());
    return list;
  };
  nlohmann::json stacks = nlohmann::json::array();
  for (const std::string& name : names("stacks")) {
    const nlohmann::json manifest = read_json_or_null(folder("stacks", name) / "manifest.json");
    nlohmann::json stack = {{"name", name}, {"frames", 0}, {"planned", nullptr}, {"complete", false}};
    if (manifest.is_object() && manifest.contains("capture")) {
      const nlohmann::json& capture = manifest["capture"];
      stack["frames"] = manifest.value("frames", nlohmann::json::array()).size();
      stack["planned"] = capture.value("plan_led_ids", nlohmann::json::array()).size();
      stack["complete"] = capture.value("complete", false);
      stack["width"] = manifest.value("width", 0);
      stack["height"] = manifest.value("height", 0);
    }
    stack["resumable"] = !stack["complete"].get<bool>() &&
                         fs::exists(options_.data / ".station" / "captures" / (name + ".json"));
    stacks.push_back(stack);
  }
  nlohmann::json calibrations = nlohmann::json::array();
  for (const std::string& name : names("calibrations")) {
    const fs::path dir = folder("calibrations", name);
    calibrations.push_back(
        {{"name", name},
         {"ready", fs::exists(dir / "calibration.json")},
         {"plot", fs::exists(dir / "lights_hemisphere.png") ? "lights_hemisphere.png" : ""}});
  }
  nlohmann::json results = nlohmann::json::array();
  for (const std::string& name : names("results")) {
    const fs::path dir = folder("results", name);
    const nlohmann::json summary = read_json_or_null(dir / "summary.json");
    nlohmann::json files = nlohmann::json::array();
    for (const char* file : {"report.html", "normal.png", "normal.exr", "albedo.png", "summary.json"}) {
      if (fs::exists(dir / file)) files.push_back(std::string("results/") + name + "/" + file);
    }
    for (const char* file : {"depth.pfm", "mesh.ply", "mesh.obj"}) {
      if (fs::exists(folder("surfaces", name) / file))
        files.push_back(std::string("surfaces/") + name + "/" + file);
    }
    nlohmann::json exports = nlohmann::json::object();
    for (const auto& [format, extension] : {std::pair{"ptm", ".ptm"}, std::pair{"hsh", ".rti"}}) {
      if (fs::exists(options_.data / "exports" / (name + extension)))
        exports[format] = "exports/" + name + extension;
    }
    results.push_back({{"name", name},
                       {"method", summary.is_object() ? summary.value("method", "") : ""},
                       {"files", files},
                       {"exports", exports}});
  }
  return {{"stacks", stacks}, {"calibrations", calibrations}, {"results", results}};
}

void Station::set_leds(const LedsRequest& request) {
  for (const auto& [id, level] : request.levels) {
    if (std::none_of(rig_.leds.begin(), rig_.leds.end(),
                     [id = id](const Led& led) { return led.id == static_cast<int>(id); }))
      throw Refused(400, fmt::format("leds: the rig '{}' has no LED {}", rig_.name, id));
  }
  std::unique_lock lock(dome_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) throw Refused(409, "the dome is busy with the running job");
  try {
    dome()->controller->set_leds(request.levels);
  } catch (const ControllerError& e) {
    throw Refused(e.code() == proto::Error::BAD_REQUEST ? 400 : 409,
                  fmt::format("the controller refused: {}", e.what()));
  } catch (const std::exception& e) {
    drop_dome(e.what());
    throw;
  }
  set_lit(request.levels, true);
}

void Station::dark() {
  {
    const std::lock_guard lock(job_mutex_);
    if (job_ && job_->running() && (job_->kind() == "capture" || job_->kind() == "test-sequence")) {
      darkened_ = true;  // its sequence is cut short below: that is a pause, not a failure
      job_->request_stop();
    }
  }
  std::shared_ptr<pipeline::DomeConnection> connection = connected();
  if (!connection) {
    // Not connected: connect now when no one else is talking to the dome.
    std::unique_lock lock(dome_mutex_, std::try_to_lock);
    if (!lock.owns_lock()) throw Error("the dome is not connected: its watchdog darkens it");
    try {
      connection = dome();
    } catch (const std::exception& e) {
      drop_dome(e.what());
      throw Error(fmt::format("the dome is not connected ({}): its watchdog darkens it", e.what()));
    }
  }
  ControllerClient& controller = *connection->controller;
  try {
    // Whatever sequence runs (a capture's, which keeps the frames it took and
    // resumes; the test sequence; a preview's) ends now, dark.
    try {
      controller.abort();
    } catch (const ControllerError&) {
      // Refused: no sequence runs.
    }
    controller.all_off();
  } catch (const ControllerError& e) {
    throw Refused(409, fmt::format("the controller refused to darken: {}", e.what()));
  } catch (const std::exception& e) {
    drop_dome(e.what());
    throw;
  }
  set_lit({}, false);
}

Preview Station::preview(const PreviewRequest& request) {
  const Led* led = nullptr;
  try {
    led = &rig_.led(static_cast<int>(request.led));
  } catch (const InputError&) {
    throw Refused(400, fmt::format("preview.led: the rig '{}' has no LED {}", rig_.name, request.led));
  }
  if (led->limits.max_on_us > 0 && request.exposure_us > led->limits.max_on_us)
    throw Refused(400, fmt::format("preview.exposure_us: {} us is longer than LED {} may stay on ({} us)",
                                   request.exposure_us, request.led, led->limits.max_on_us));
  std::unique_lock lock(dome_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) throw Refused(409, "the dome is busy with the running job");
  CaptureOptions options;
  options.gain = request.gain;
  options.mode = OutputMode::kQuiet;
  std::vector<cv::Mat> frames;
  try {
    const auto connection = dome();
    set_lit({{request.led, 1.0f}}, false);
    frames = capture_bracket(rig_, *connection->controller, *connection->camera,
                             static_cast<int>(request.led), {request.exposure_us}, options);
    set_lit({}, false);
  } catch (const InputError& e) {
    set_lit({}, false);
    throw Refused(400, e.what());
  } catch (const ControllerError& e) {
    set_lit({}, false);
    throw Refused(e.code() == proto::Error::BAD_REQUEST ? 400 : 409,
                  fmt::format("the controller refused: {}", e.what()));
  } catch (const BatchAborted& e) {
    set_lit({}, false);  // the dome was darkened meanwhile (or the controller's limits cut it short)
    throw Refused(409, fmt::format("the preview was cut short: {}", e.what()));
  } catch (const std::exception& e) {
    drop_dome(e.what());
    throw;
  }
  return {encode_preview_png(frames.front()), preview_figures(frames.front())};
}

void Station::place(const std::string& what) {
  if (!bench_) throw Refused(400, "place: this station runs a real dome; place the object by hand");
  bench_->check_choice(what);
  {
    const std::lock_guard lock(job_mutex_);
    if (job_ && job_->running()) throw Refused(409, fmt::format("a {} is running", job_->kind()));
  }
  const std::unique_lock lock(dome_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) throw Refused(409, "the dome is busy: place the object when it is free");
  drop_dome("");
  bench_->place(what);
  try {
    dome();
  } catch (const std::exception& e) {
    drop_dome(e.what());
  }
}

nlohmann::json Station::start_job(const std::string& kind, nlohmann::json request, bool stoppable,
                                  Work work) {
  const std::lock_guard lock(job_mutex_);
  if (job_ && job_->running())
    throw Refused(409, fmt::format("a {} is running: stop it or wait for it to end", job_->kind()));
  job_.reset();  // the last one ended: its thread is joined
  abort_ = false;
  darkened_ = false;
  job_ = std::make_shared<StationJob>(next_job_id_++, kind, std::move(request), stoppable, std::move(work));
  return job_->to_json();
}

void Station::stop_job(bool abort) {
  std::string kind;
  {
    const std::lock_guard lock(job_mutex_);
    if (!job_ || !job_->running()) throw Refused(409, "no job is running");
    if (!job_->stoppable())
      throw Refused(409, fmt::format("a {} cannot be stopped: it ends by itself", job_->kind()));
    abort_ = abort;
    job_->request_stop();
    kind = job_->kind();
  }
  // Its one sequence walks every LED: cut short now, not at its end.
  if (kind == "test-sequence") abort_sequence();
}

nlohmann::json Station::job_json() const {
  const std::lock_guard lock(job_mutex_);
  return job_ ? job_->to_json() : nlohmann::json(nullptr);
}

void Station::wait_job() {
  std::shared_ptr<StationJob> job;
  {
    const std::lock_guard lock(job_mutex_);
    job = job_;
  }
  if (job) job->wait();
}

fs::path Station::existing_stack(const std::string& name) const {
  check_folder_name(name, "stack");
  const fs::path stack = folder("stacks", name);
  if (!fs::exists(stack / "filenames.txt")) throw Refused(404, fmt::format("no stack '{}'", name));
  return stack;
}

nlohmann::json Station::sphere(const std::string& name) const {
  const calibration::CalibrationImages images = calibration::load_calibration_index(existing_stack(name));
  nlohmann::json j = {{"stack", name},
                      {"width", images.width()},
                      {"height", images.height()},
                      {"circle", nullptr},
                      {"error", ""}};
  j["drawn"] = drawn_here(folder("stacks", name), options_.data / ".station" / "spheres" / (name + ".json"));
  try {
    const calibration::LightCalibrationOptions defaults;
    const cv::Mat median = images.mask.empty() ? calibration::calibration_views(images).median : cv::Mat();
    const auto circles = calibration::find_sphere_circles(images, median, defaults);
    const calibration::ImageCircle& c = circles.front();
    j["circle"] = {{"x_px", c.centre_px.x()},
                   {"y_px", c.centre_px.y()},
                   {"radius_px", c.radius_px},
                   {"source", c.source},
                   {"rms_px", c.rms_px}};
  } catch (const InputError& e) {
    j["error"] = e.what();  // not found: the operator draws it
  }
  return j;
}

std::string Station::sphere_png(const std::string& name) const {
  const calibration::CalibrationImages images = calibration::load_calibration_index(existing_stack(name));
  const cv::Mat brightest = calibration::calibration_views(images).maximum;
  // A square root lifts the dim rim of a chrome sphere in a dark dome out of the black.
  cv::Mat lifted;
  cv::sqrt(cv::max(brightest, 0.0), lifted);
  return encode_preview_png(cv::min(lifted, 1.0));
}

nlohmann::json Station::set_sphere(const std::string& name, const SphereCircle& circle) {
  const fs::path stack = existing_stack(name);
  const fs::path marker = options_.data / ".station" / "spheres" / (name + ".json");
  if (fs::exists(stack / "mask.png") && !drawn_here(stack, marker))
    throw Refused(409, fmt::format("stacks/{}/mask.png was not drawn here: it is left as it is", name));
  const nlohmann::json manifest = read_json_or_null(stack / "manifest.json");
  const int width = manifest.is_object() ? manifest.value("width", 0) : 0;
  const int height = manifest.is_object() ? manifest.value("height", 0) : 0;
  if (width <= 0 || height <= 0)
    throw Refused(400, fmt::format("stacks/{}: its manifest gives no image size", name));
  if (circle.x_px > width || circle.y_px > height)
    throw Refused(400, fmt::format("sphere: the centre ({}, {}) is outside the {}x{} image", circle.x_px,
                                   circle.y_px, width, height));
  // A disk, drawn with 8 bits of sub-pixel precision; pixel centres at +0.5.
  cv::Mat mask(height, width, CV_8UC1, cv::Scalar(0));
  constexpr int kShift = 8;
  const auto fixed = [](double v) { return static_cast<int>(std::lround(v * (1 << kShift))); };
  cv::circle(mask, cv::Point(fixed(circle.x_px - 0.5), fixed(circle.y_px - 0.5)), fixed(circle.radius_px),
             cv::Scalar(255), cv::FILLED, cv::LINE_8, kShift);
  // The marker first, then the mask renamed into place: a crash between them
  // leaves no mask, never one that looks like the operator's own.
  const fs::path drawing = stack / ".mask-drawn.png";
  io::write_png(drawing, mask);
  write_json_atomically(marker, {{"x_px", circle.x_px},
                                 {"y_px", circle.y_px},
                                 {"radius_px", circle.radius_px},
                                 {"mask_hash", content_hash(file_bytes(drawing))}});
  fs::rename(drawing, stack / "mask.png");
  return sphere(name);
}

nlohmann::json Station::forget_sphere(const std::string& name) {
  const fs::path stack = existing_stack(name);
  const fs::path marker = options_.data / ".station" / "spheres" / (name + ".json");
  if (!drawn_here(stack, marker))
    throw Refused(
        409, fmt::format("stacks/{}: no outline drawn here (its mask.png, if any, is left as it is)", name));
  fs::remove(stack / "mask.png");
  fs::remove(marker);
  return sphere(name);
}

nlohmann::json Station::start_test_sequence(const TestSequenceRequest& request) {
  for (const Led& led : rig_.leds) {
    if (led.limits.max_on_us > 0 && request.on_us > led.limits.max_on_us)
      throw Refused(400, fmt::format("test-sequence.on_us: {} us is longer than LED {} may stay on ({} us)",
                                     request.on_us, led.id, led.limits.max_on_us));
  }
  return start_job("test-sequence", {{"on_us", request.on_us}}, true,
                   [this, request](StationJob& job) { return test_sequence_work(job, request); });
}

nlohmann::json Station::test_sequence_work(StationJob& job, const TestSequenceRequest& request) {
  const std::lock_guard lock(dome_mutex_);
  try {
    const auto connection = dome();
    ControllerClient& controller = *connection->controller;
    const std::vector<std::uint32_t> ids = led_ids(controller.info());
    job.progress(0, ids.size(), "LEDs");
    if (job.stop_requested()) throw JobStopped("the test sequence was stopped before it started");
    OneLedPerStepOptions steps_options;
    steps_options.exposure_us = request.on_us;
    std::size_t steps = 0;
    bool aborted = false;
    const SequenceRun run =
        controller.run_sequence(one_led_per_step(ids, steps_options, 1), [&](const proto::StepEvent& step) {
          if (job.stop_requested() && !aborted) {  // a stop asked for before the run began
            aborted = true;
            try {
              controller.abort();
            } catch (const ControllerError&) {
              // The run ended meanwhile.
            }
          }
          std::vector<std::pair<std::uint32_t, float>> lit;
          for (const std::uint32_t id : step.led_ids()) lit.emplace_back(id, 1.0f);
          set_lit(std::move(lit), false);
          job.progress(++steps, ids.size(), "LEDs");
        });
    set_lit({}, false);
    const LatenessStats lateness = lateness_stats(run.steps);
    if (job.stop_requested() && run.done.outcome() == proto::ABORTED_BY_HOST)
      throw JobStopped(
          fmt::format("the test sequence was stopped after {} of {} LEDs", run.steps.size(), ids.size()));
    if (!run.ok())
      throw Error(fmt::format("the test sequence ended early: {} {}", proto::Outcome_Name(run.done.outcome()),
                              run.done.detail()));
    return {{"steps", run.steps.size()},
            {"lateness_us",
             {{"median", lateness.median_ns / 1e3},
              {"p99", lateness.p99_ns / 1e3},
              {"max", lateness.max_ns / 1e3}}}};
  } catch (const ControllerError&) {
    set_lit({}, false);
    throw;
  } catch (const JobStopped&) {
    throw;
  } catch (const std::exception& e) {
    drop_dome(e.what());
    throw;
  }
}

nlohmann::json Station::start_capture(const CaptureRequest& request) {
  const fs::path out = folder("stacks", request.name);
  if (fs::exists(out))
    throw Refused(409,
                  fmt::format("stacks/{} exists: resume it, or capture under another name", request.name));
  {
    const std::lock_guard lock(job_mutex_);
    if (job_ && job_->running())
      throw Refused(409, fmt::format("a {} is running: stop it or wait for it to end", job_->kind()));
  }
  // The request is kept so that a resume (after a stop, a crash, a lost link) repeats it exactly.
  write_json_atomically(options_.data / ".station" / "captures" / (request.name + ".json"),
                        request.to_json());
  return start_job("capture", request.to_json(), true,
                   [this, request](StationJob& job) { return capture_work(job, request, false); });
}

nlohmann::json Station::resume_capture(const std::string& name) {
  check_folder_name(name, "resume.name");
  const nlohmann::json asked = read_json_or_null(options_.data / ".station" / "captures" / (name + ".json"));
  if (!asked.is_object())
    throw Refused(404, fmt::format("stacks/{}: no capture of this station to resume", name));
  const CaptureRequest request = capture_request(asked);
  nlohmann::json shown = request.to_json();
  shown["resume"] = true;
  return start_job("capture", shown, true,
                   [this, request](StationJob& job) { return capture_work(job, request, true); });
}

nlohmann::json Station::capture_work(StationJob& job, const CaptureRequest& request, bool resume) {
  CaptureOptions options;
  options.out = folder("stacks", request.name);
  options.resume = resume;
  options.exposure_us = request.exposure_us;
  options.dark_frames = request.dark_frames;
  options.bracket_stops = request.bracket_stops;
  options.led_ids = request.led_ids;
  if (request.chrome_sphere) {
    options.auto_percentile = 1.0;
    options.auto_target = 0.7;
  }
  options.mode = OutputMode::kQuiet;
  options.on_progress = [&](const CaptureProgress& progress) {
    job.progress(progress.frames, progress.total, "frames");
    set_lit({{static_cast<std::uint32_t>(progress.led_id), 1.0f}}, false);
  };
  options.stop_requested = [&] { return job.stop_requested(); };
  options.halt_requested = [this] { return darkened_.load(); };
  set_lit({}, false);  // what was lit by hand goes out with the first sequence: not the lease's to darken
  job.say(resume ? "resuming" : "capturing");
  const std::lock_guard lock(dome_mutex_);
  try {
    const auto connection = dome();
    const CaptureReport report = capture_stack(rig_, *connection->controller, *connection->camera, options);
    set_lit({}, false);
    nlohmann::json result = report.to_json();
    result["stack"] = request.name;
    return result;
  } catch (const InputError&) {
    set_lit({}, false);
    throw;
  } catch (const CaptureStopped& e) {
    set_lit({}, false);
    if (!abort_) throw JobStopped(e.what());
    // Aborted: the frames stay on disk, the plan goes (the page offers no resume).
    fs::remove(options_.data / ".station" / "captures" / (request.name + ".json"));
    throw JobStopped(
        fmt::format("the capture was aborted; the frames taken are kept in stacks/{}", request.name));
  } catch (const std::exception& e) {
    set_lit({}, false);
    drop_dome(e.what());
    throw;
  }
}

nlohmann::json Station::start_calibration(const CalibrationRequest& request) {
  for (const std::string& stack : request.stacks) {
    if (!fs::exists(folder("stacks", stack) / "manifest.json"))
      throw Refused(404, fmt::format("calibration.stacks: no stack '{}'", stack));
  }
  if (fs::exists(folder("calibrations", request.name)))
    throw Refused(409, fmt::format("calibrations/{} exists: choose another name", request.name));
  return start_job("calibration", request.to_json(), false,
                   [this, request](StationJob& job) { return calibration_work(job, request); });
}

nlohmann::json Station::calibration_work(StationJob& job, const CalibrationRequest& request) {
  calibration::LightCalibrationOptions options;
  for (const std::string& stack : request.stacks) options.inputs.push_back(folder("stacks", stack));
  options.rig = options_.rig;
  // Two positions or more: LED positions triangulated, no help from the nominal dome.
  if (options.inputs.size() >= 2) options.dome_radius_mm = 0;
  options.sphere_z_mm = {rig_.object_position_mm.z()};
  options.allow_missing = request.allow_missing;
  job.say("finding the highlights");
  const auto run = calibration::calibrate_lights(options);
  const fs::path out = folder("calibrations", request.name);
  nlohmann::json written = calibration::write_calibration_outputs(out, run, options.inputs);
  std::size_t measured = 0;
  for (const auto& light : run.calibration.lights) measured += light.measured ? 1 : 0;
  return {{"name", request.name},   {"lights", run.calibration.lights.size()},
          {"measured", measured},   {"problems", run.calibration.problems},
          {"seconds", run.seconds}, {"written", written}};
}

nlohmann::json Station::start_solve(const SolveRequest& request) {
  const auto names = methods();
  if (std::find(names.begin(), names.end(), request.method) == names.end())
    throw Refused(
        400, fmt::format("solve.method: '{}' is not a method (GET /api/methods lists them)", request.method));
  if (!fs::exists(folder("stacks", request.stack) / "manifest.json"))
    throw Refused(404, fmt::format("solve.stack: no stack '{}'", request.stack));
  if (!request.calibration.empty() &&
      !fs::exists(folder("calibrations", request.calibration) / "calibration.json"))
    throw Refused(404, fmt::format("solve.calibration: no calibration '{}'", request.calibration));
  for (const char* kind : {"results", "surfaces"}) {
    if (fs::exists(folder(kind, request.name)))
      throw Refused(409, fmt::format("{}/{} exists: choose another name", kind, request.name));
  }
  return start_job("solve", request.to_json(), true,
                   [this, request](StationJob& job) { return solve_work(job, request); });
}

nlohmann::json Station::start_export(const std::string& result, const std::string& format) {
  check_folder_name(result, "export.result");
  if (format != "ptm" && format != "hsh")
    throw Refused(400, fmt::format("export.format: '{}' is neither ptm nor hsh", format));
  if (!fs::exists(folder("results", result) / "summary.json"))
    throw Refused(404, fmt::format("export.result: no result '{}'", result));
  const fs::path out = options_.data / "exports" / (result + (format == "ptm" ? ".ptm" : ".rti"));
  if (fs::exists(out)) throw Refused(409, fmt::format("exports/{} exists", out.filename().string()));
  return start_job(
      "export", {{"result", result}, {"format", format}}, false,
      [this, result, format, out](StationJob& job) {
        pipeline::ExportSettings settings;
        settings.input = folder("results", result);
        settings.out = out;
        settings.format = format;
        job.say(fmt::format("fitting the {} of every pixel", format == "ptm" ? "polynomial" : "harmonics"));
        nlohmann::json written = pipeline::export_rti(settings);
        written["file"] = "exports/" + out.filename().string();
        return written;
      });
}

nlohmann::json Station::solve_work(StationJob& job, const SolveRequest& request) {
  const fs::path out = folder("results", request.name);
  const fs::path surface = folder("surfaces", request.name);
  try {
    return solve_stages(job, request);
  } catch (const JobStopped&) {
    // Half a result is no result: the folders this solve wrote go (their names were free before it).
    std::error_code ignored;
    fs::remove_all(out, ignored);
    fs::remove_all(surface, ignored);
    throw;
  }
}

nlohmann::json Station::solve_stages(StationJob& job, const SolveRequest& request) {
  const auto stop_point = [&job] {
    if (job.stop_requested()) throw JobStopped("the solve was stopped; its partial result is removed");
  };
  const fs::path stack = folder("stacks", request.stack);
  const fs::path out = folder("results", request.name);
  pipeline::SolveSettings settings;
  settings.method = request.method;
  settings.resolve();
  pipeline::SolveCalibration calibration;
  if (!request.calibration.empty())
    calibration.file = folder("calibrations", request.calibration) / "calibration.json";
  job.say("solving");
  const pipeline::SolveReport solved = pipeline::solve_folder(
      stack, settings, out, calibration, [&job, stop_point](const pipeline::SolveWork& work) {
        auto done = std::make_shared<std::atomic<std::size_t>>(0);
        job.progress(0, work.total, work.unit);
        // Called from the solver's workers: a stop ends the solve there (its threads pass the error on).
        return SolveProgress([&job, done, work, stop_point](std::size_t items) {
          stop_point();
          job.progress(*done += items, work.total, work.unit);
        });
      });
  stop_point();
  job.say("integrating the surface");
  pipeline::IntegrateSettings integrate;
  integrate.input = out.string();
  const fs::path surface = folder("surfaces", request.name);
  integrate.out = surface.string();
  stop_point();
  // Orthographic: the rig camera's pixel at the object, scaled to the stack's width.
  const int width = solved.summary.value("width", rig_.camera.width);
  integrate.pixel_mm = rig_.camera.pixel_pitch_mm * rig_.camera.width / std::max(1, width);
  pipeline::integrate_folder(integrate);
  stop_point();
  job.say("writing the report");
  report::ReportOptions report_options;
  report_options.stack = stack;
  if (!calibration.file.empty()) report_options.calibration = calibration.file;
  report_options.depth = surface;
  report::write_report(out, out / "report.html", report_options);
  nlohmann::json result = {{"name", request.name},
                           {"report", "results/" + request.name + "/report.html"},
                           {"surface", "surfaces/" + request.name}};
  if (solved.error) result["error_vs_ground_truth"] = solved.error->to_json();
  return result;
}

}  // namespace lightstage::station
