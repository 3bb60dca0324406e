#include "lightstage/host/capture/stack_writer.hpp"

#include "io/image_header.hpp"
#include "io/stack_manifest.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/capture/hdr_merge.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "util/utc_time.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>

namespace fs = std::filesystem;

namespace lightstage {
namespace {

double full_scale(const camera::Frame& f) { return std::ldexp(1.0, f.bit_depth) - 1; }

// The camera's stamps of a frame and the controller's of its step.
nlohmann::json stamps(const Taken& taken) {
  nlohmann::json out = {{"frame_sequence", taken.frame.sequence},
                        {"frame_timestamp_ns", taken.frame.timestamp_ns},
                        {"frame_clock", std::string(camera::to_string(taken.frame.clock))},
                        {"trigger_ns", taken.step.trigger_ns()},
                        {"leds_on_ns", taken.step.leds_on_ns()},
                        {"leds_off_ns", taken.step.leds_off_ns()}};
  // A stills camera's shot: its own file stays where it arrived (the original, e.g. the RAW).
  if (!taken.frame.source_file.empty()) {
    out["source_image"] = taken.frame.source_file;
    out["frame_clock"] = "camera";
  }
  return out;
}

std::string exposure_text(const std::optional<double>& fixed_us) {
  return fixed_us ? fmt::format("--exposure-us {}", *fixed_us) : std::string("automatic exposure");
}

// A resumed capture goes on at the exposures it was planned with; a run asking
// for others would mix them silently, so it is refused as other LEDs are.
void check_same_exposure(const fs::path& manifest_path, const io::CaptureManifest& manifest,
                         const std::optional<double>& asked_us) {
  if (manifest.fixed_exposure) {
    const std::optional<double> planned =
        *manifest.fixed_exposure ? manifest.fixed_exposure_us : std::optional<double>();
    if (planned != asked_us) {
      fail("{}: cannot resume: it was planned with {}, this run asks for {}", manifest_path.string(),
           exposure_text(planned), exposure_text(asked_us));
    }
    return;
  }
  // Written before the choice was recorded: a fixed exposure must be every LED's.
  if (!asked_us) return;
  for (const auto& [id, exposure_us] : manifest.exposure_us) {
    if (exposure_us != *asked_us) {
      fail("{}: cannot resume: LED {} was planned at {} us, this run asks for --exposure-us {}",
           manifest_path.string(), id, exposure_us, *asked_us);
    }
  }
}

}  // namespace

CaptureStackWriter::CaptureStackWriter(const Rig& rig, fs::path out, const InverseResponse* response)
    : rig_(rig), out_(std::move(out)), response_(response) {}

PreviousPlan CaptureStackWriter::resume(const std::vector<int>& led_ids, const CaptureOptions& asked) {
  const std::vector<double>& bracket_stops = asked.bracket_stops;
  const fs::path manifest_path = out_ / "manifest.json";
  if (!fs::exists(manifest_path)) return {};
  io::CaptureManifest manifest = io::read_capture_manifest(manifest_path);
  if (manifest.plan_led_ids != led_ids) {
    fail("{}: cannot resume: it was planned for other LEDs ({} of them) than this run ({})",
         manifest_path.string(), manifest.plan_led_ids.size(), led_ids.size());
  }
  if (manifest.bracket_stops != bracket_stops) {
    fail("{}: cannot resume: it was planned with bracket stops [{}], this run asks for [{}]",
         manifest_path.string(), fmt::join(manifest.bracket_stops, ","), fmt::join(bracket_stops, ","));
  }
  check_same_exposure(manifest_path, manifest, asked.exposure_us);
  if (manifest.dark_frames && *manifest.dark_frames != asked.dark_frames) {
    fail("{}: cannot resume: it was planned with --dark-frames {}, this run asks for {}",
         manifest_path.string(), *manifest.dark_frames, asked.dark_frames);
  }
  for (io::CaptureDark& dark : manifest.darks)
    resumed_darks_.emplace_back(dark.exposure_us, Dark{std::move(dark.file), dark.mean, {}});
  // The frames the manifest lists (written after each frame's image, so every
  // frame it names is complete on disk; a frame in flight when the capture
  // stopped is simply taken again).
  for (std::size_t k = 0; k < manifest.done.size() && k < manifest.frames.size(); ++k) {
    const std::size_t index = manifest.done[k];
    if (index >= led_ids.size())
      fail("{}: capture.done[{}] = {} is past the plan", manifest_path.string(), k, index);
    io::ManifestFrame& listed = manifest.frames[k];
    if (listed.frame.led_id != led_ids[index]) {
      fail("{}: frames[{}] is LED {}, but the plan has LED {} there", manifest_path.string(), k,
           listed.frame.led_id, led_ids[index]);
    }
    io::read_image_header(out_ / listed.frame.filename);  // there, and an image (errors name the file)
    frames_[index] = std::move(listed.frame);
    frame_extra_[index] = std::move(listed.extra);
  }
  logger("capture")->info("resuming {}: {} of {} frames already taken", out_.string(), frames_.size(),
                          led_ids.size());
  return {std::move(manifest.exposure_us), std::move(manifest.bracket_exposure_us)};
}

void CaptureStackWriter::set_plan(const CapturePlan& plan, const CaptureSetup& setup) {
  plan_ = plan;
  setup_ = setup;
  darks_.assign(plan_.exposures_us.size(), std::nullopt);
  for (auto& [exposure_us, dark] : resumed_darks_) {
    for (std::size_t e = 0; e < plan_.exposures_us.size(); ++e) {
      if (plan_.exposures_us[e] == exposure_us) darks_[e] = std::move(dark);
    }
  }
  resumed_darks_.clear();
}

std::vector<bool> CaptureStackWriter::done() const {
  std::vector<bool> done(plan_.frames.size(), false);
  for (const auto& [i, frame] : frames_) done[i] = true;
  return done;
}

bool CaptureStackWriter::has_dark(std::size_t exposure) const {
  return exposure < darks_.size() && darks_[exposure].has_value();
}

void CaptureStackWriter::write_image(const std::string& name, const cv::Mat& image) const {
  if (image.depth() == CV_32F) {
    io::write_pfm(out_ / name, image);
  } else {
    io::write_png(out_ / name, image);
  }
}

void CaptureStackWriter::add_dark(std::size_t exposure, const std::vector<cv::Mat>& frames) {
  if (frames.empty()) fail("capture: no frames for the dark at {} us", plan_.exposures_us.at(exposure));
  cv::Mat sum;
  for (const cv::Mat& image : frames) {
    cv::Mat f;
    (response_ ? response_->linearise(image) : image).convertTo(f, CV_64F);
    sum = sum.empty() ? f : sum + f;
  }
  Dark dark;
  sum.convertTo(dark.image, response_ ? CV_32F : CV_16U, 1.0 / static_cast<double>(frames.size()));
  dark.file = fmt::format("dark_{:.0f}us.{}", plan_.exposures_us.at(exposure), response_ ? "pfm" : "png");
  write_image(dark.file, dark.image);
  dark.mean = cv::mean(dark.image)[0];
  darks_.at(exposure) = std::move(dark);
}

cv::Mat CaptureStackWriter::dark_image(std::size_t exposure) {
  if (!has_dark(exposure)) return {};  // no darks: black level 0
  Dark& dark = *darks_[exposure];
  if (dark.image.empty()) dark.image = io::read_image(out_ / dark.file);  // taken before an interruption
  return dark.image;
}

void CaptureStackWriter::add_frame(std::size_t index, const Take& take) {
  const PlannedFrame& planned = plan_.frames.at(index);
  const Taken& taken = take.taken;
  const Led& led = rig_.led(planned.led_id);
  const double exposure = taken.frame.exposure_us > 0 ? taken.frame.exposure_us : plan_.exposure_us(index);
  Frame frame;
  frame.filename = fmt::format("{:03}.{}", index + 1, response_ ? "pfm" : "png");
  frame.image = response_ ? response_->linearise(taken.frame.image) : taken.frame.image;
  frame.led_id = planned.led_id;
  frame.led_position_mm = led.position_mm;
  frame.light_direction = rig_.light_direction(led);
  // Radiometry divides by this: values become radiance per the rig's reference exposure and gain.
  const double scale = (exposure / rig_.camera.exposure_us) * (taken.frame.analogue_gain / rig_.camera.gain);
  frame.light_intensity = Vec3::Constant(led.relative_intensity * scale);
  frame.exposure_us = exposure;
  frame.gain = taken.frame.analogue_gain;
  frame.black_level = has_dark(planned.exposure) ? darks_[planned.exposure]->mean : 0;
  if (has_dark(planned.exposure)) {
    frame.dark_file = darks_[planned.exposure]->file;
    frame.dark = dark_image(planned.exposure);
  }
  write_image(frame.filename, frame.image);
  frame.image.release();  // on disk now: a capture holds no frame's pixels (the index needs none)
  frames_[index] = std::move(frame);
  frame_extra_[index] = stamps(taken);
}

void CaptureStackWriter::add_hdr_frame(std::size_t index, const std::vector<Take>& takes) {
  const PlannedFrame& planned = plan_.frames.at(index);
  const Led& led = rig_.led(planned.led_id);
  std::vector<HdrSample> samples;
  nlohmann::json exposures = nlohmann::json::array(), details = nlohmann::json::array();
  for (const Take& take : takes) {
    const Taken& taken = take.taken;
    const double exposure =
        taken.frame.exposure_us > 0 ? taken.frame.exposure_us : plan_.exposures_us.at(take.exposure);
    samples.push_back({taken.frame.image, dark_image(take.exposure), exposure});
    exposures.push_back(exposure);
    nlohmann::json detail = stamps(taken);
    detail["exposure_us"] = exposure;
    if (has_dark(take.exposure)) detail["dark"] = darks_[take.exposure]->file;
    details.push_back(std::move(detail));
  }
  HdrMergeOptions merge_options;
  merge_options.sensor_full_scale = full_scale(takes.front().taken.frame);
  merge_options.saturation_dn = kClippedShare * merge_options.sensor_full_scale;
  merge_options.response = response_;
  const HdrMerge merged = merge_hdr(samples, merge_options);
  for (std::size_t i = 0; i < details.size(); ++i) details[i]["clipped_values"] = merged.clipped[i];

  const double gain = takes.front().taken.frame.analogue_gain;
  Frame frame;
  frame.filename = fmt::format("{:03}.pfm", index + 1);
  frame.image = merged.image;
  frame.led_id = planned.led_id;
  frame.led_position_mm = led.position_mm;
  frame.light_direction = rig_.light_direction(led);
  // Values are per exposure-second: as if exposed for 1 s, dark already subtracted.
  constexpr double kSecondUs = 1e6;
  const double scale = (kSecondUs / rig_.camera.exposure_us) * (gain / rig_.camera.gain);
  frame.light_intensity = Vec3::Constant(led.relative_intensity * scale);
  frame.exposure_us = kSecondUs;
  frame.gain = gain;
  frame.black_level = 0;
  frame.saturation_level = merged.saturation_level;
  io::write_pfm(out_ / frame.filename, frame.image);
  frame.image.release();
  frames_[index] = std::move(frame);
  frame_extra_[index] = {{"bracket_exposures_us", exposures},
                         {"bracket", details},
                         {"hdr_saturated_values", merged.saturated_values}};
}

void CaptureStackWriter::write_index(bool complete) {
  ImageStack stack;
  nlohmann::json extra_frames = nlohmann::json::array();
  std::vector<int> done;
  for (const auto& [i, frame] : frames_) {
    stack.frames.push_back(frame);
    extra_frames.push_back(frame_extra_[i]);
    done.push_back(static_cast<int>(i));
  }
  nlohmann::json exposures = nlohmann::json::object();
  nlohmann::json brackets = nlohmann::json::object();
  for (std::size_t i = 0; i < plan_.frames.size(); ++i) {
    const PlannedFrame& planned = plan_.frames[i];
    exposures[std::to_string(planned.led_id)] = plan_.exposure_us(i);
    if (planned.bracket.empty()) continue;
    std::vector<double> list;
    for (const std::size_t e : planned.bracket) list.push_back(plan_.exposures_us[e]);
    brackets[std::to_string(planned.led_id)] = list;
  }
  nlohmann::json darks = nlohmann::json::object();
  for (std::size_t e = 0; e < darks_.size(); ++e) {
    if (!darks_[e]) continue;
    const double exposure_us = plan_.exposures_us[e];
    darks[fmt::format("{:.0f}", exposure_us)] = {
        {"file", darks_[e]->file}, {"mean", darks_[e]->mean}, {"exposure_us", exposure_us}};
  }
  nlohmann::json extra = {
      {"capture",
       {{"version", io::kCaptureFormatVersion},
        {"complete", complete},
        {"plan_led_ids", plan_.led_ids()},
        {"done", done},
        {"exposure_us", exposures},
        {"gain", setup_.gain},
        {"loop", setup_.closed_loop ? "closed" : "open"},
        {"trigger", setup_.hardware_trigger ? "hardware" : "software"},
        {"darks", darks},
        {"dark_frames", plan_.dark_frames},
        {"fixed_exposure_us",
         setup_.fixed_exposure_us ? nlohmann::json(*setup_.fixed_exposure_us) : nlohmann::json()},
        {"bracket_stops", plan_.bracket_stops},
        {"bracket_exposure_us", brackets},
        {"camera",
         {{"uri", setup_.camera.uri}, {"model", setup_.camera.model}, {"driver", setup_.camera.driver}}},
        {"controller", {{"firmware", setup_.controller_firmware}, {"rig", setup_.controller_rig}}},
        {"updated", util::utc_timestamp()}}},
      {"rig", {{"name", rig_.name}, {"file", rig_.source.string()}}},
      {"frames", extra_frames}};
  // What solve must (not) do to the frames: linearised here, or as the camera gave them.
  extra["radiometry"] =
      response_
          ? nlohmann::json{{"linear", true}, {"response_applied", true}, {"response", response_->to_json()}}
          : nlohmann::json{{"response_applied", false}};
  if (stack.frames.empty()) {
    // Nothing to index yet: keep the plan where resume can find it.
    io::write_empty_stack(out_, nlohmann::json{{"format", io::kStackFormat},
                                               {"version", io::kStackFormatVersion},
                                               {"capture", extra["capture"]}});
    return;
  }
  io::write_stack(out_, stack, extra, /*write_images=*/false);
}

}  // namespace lightstage
