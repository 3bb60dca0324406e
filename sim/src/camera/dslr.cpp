#include "lightstage/sim/camera/dslr.hpp"

#include "lightstage/common/camera.hpp"
#include "lightstage/common/clock.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <chrono>
#include <cmath>
#include <system_error>

namespace lightstage::sim {
namespace {

namespace fs = std::filesystem;

// A raw file's black level when the sensor model has none.
constexpr double kDefaultBlackLevel = 512;
// The camera never looks further back than this before a shot's exposure.
constexpr std::int64_t kHistoryNs = 1'000'000'000;

// The number in "IMG_<digits>[.ext]" (any case), or nullopt for any other name.
std::optional<std::uint64_t> image_number(const std::string& name) {
  if (name.size() < 5) return std::nullopt;
  std::string prefix = name.substr(0, 4);
  std::transform(prefix.begin(), prefix.end(), prefix.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  if (prefix != "IMG_") return std::nullopt;
  const char* begin = name.data() + 4;
  const char* end = name.data() + name.size();
  std::uint64_t number = 0;
  const auto [ptr, ec] = std::from_chars(begin, end, number);
  if (ec != std::errc() || ptr == begin || (ptr != end && *ptr != '.')) return std::nullopt;
  return number;
}

// The folder, created if missing, and the number after the highest IMG_<NNNN> in it.
std::uint64_t prepare_folder(const fs::path& folder) {
  std::error_code error;
  if (fs::exists(folder, error) && !fs::is_directory(folder, error)) {
    fail("dslr: {} is not a folder", folder.string());
  }
  fs::create_directories(folder, error);
  if (error) fail("dslr: cannot create the folder {}: {}", folder.string(), error.message());
  std::uint64_t highest = 0;
  for (const auto& entry : fs::directory_iterator(folder, error)) {
    if (const auto number = image_number(entry.path().filename().string()))
      highest = std::max(highest, *number);
  }
  if (error) fail("dslr: cannot list the folder {}: {}", folder.string(), error.message());
  return highest + 1;
}

// The BGR channel of a CFA letter.
int bgr_channel(char letter) { return letter == 'R' ? 2 : letter == 'G' ? 1 : 0; }

}  // namespace

void DslrOptions::check() const {
  if (folder.empty()) fail("dslr: no folder to write the shots into");
  if (shutter_line.empty()) fail("dslr: no shutter line");
  if (!focus_line.empty() && focus_line == shutter_line)
    fail("dslr: the focus line \"{}\" is the shutter line", focus_line);
  if (exposure_us && !(*exposure_us > 0 && std::isfinite(*exposure_us)))
    fail("dslr: exposure_us must be positive, got {}", *exposure_us);
  if (iso && !(*iso > 0 && std::isfinite(*iso))) fail("dslr: iso must be positive, got {}", *iso);
  if (!(f_number > 0 && std::isfinite(f_number))) fail("dslr: f_number must be positive, got {}", f_number);
  if (lag_min_ns < 0 || lag_min_ns > lag_max_ns)
    fail("dslr: shutter lag [{}, {}] ns must have 0 <= min <= max", lag_min_ns, lag_max_ns);
  if (delay_min_ns < 0 || delay_min_ns > delay_max_ns)
    fail("dslr: card delay [{}, {}] ns must have 0 <= min <= max", delay_min_ns, delay_max_ns);
  if (buffer_shots < 1) fail("dslr: buffer_shots must be at least 1, got {}", buffer_shots);
  if (drop_shots.contains(0)) fail("dslr: drop_shots counts from 1, got 0");
  if (!(drop_rate >= 0 && drop_rate < 1)) fail("dslr: drop_rate must be in [0, 1), got {}", drop_rate);
  if (black_level && !(*black_level >= 0 && *black_level < 65535))
    fail("dslr: black_level must be in [0, 65535), got {}", *black_level);
  for (const double offset : black_offsets) {
    // Whole DN: they are added to integer samples, and raw readers keep black levels as integers.
    if (!(offset >= 0 && offset < 65535 && offset == std::floor(offset)))
      fail("dslr: black offset {} must be a whole number of DN in [0, 65535)", offset);
  }
  const std::string cfa_text(cfa.begin(), cfa.end());
  if (std::count(cfa.begin(), cfa.end(), 'R') != 1 || std::count(cfa.begin(), cfa.end(), 'G') != 2 ||
      std::count(cfa.begin(), cfa.end(), 'B') != 1) {
    fail("dslr: CFA pattern \"{}\" must have exactly one R, two G and one B", cfa_text);
  }
}

SimulatedDslr::SimulatedDslr(std::shared_ptr<const World> world, SensorOptions sensor, DslrOptions options)
    : world_(std::move(world)), options_(std::move(options)), random_(options_.seed) {
  options_.check();
  const Rig& rig = world_->rig();
  for (std::size_t i = 0; i < rig.leds.size(); ++i) led_index_[rig.leds[i].id] = i;
  exposure_us_ = options_.exposure_us.value_or(rig.camera.exposure_us);
  iso_ = options_.iso.value_or(100 * world_->sensor().gain());
  sensor.exposure_us = exposure_us_;
  sensor.gain = iso_ / 100;
  if (options_.black_level) {
    sensor.black_level = *options_.black_level;
  } else if (sensor.black_level == 0) {
    sensor.black_level = kDefaultBlackLevel;
  }
  sensor_ = std::make_unique<Sensor>(sensor, rig.camera);
  exposure_ns_ = std::llround(exposure_us_ * 1000);
  const auto blacks = black_levels();
  for (std::size_t site = 0; site < blacks.size(); ++site) {
    if (blacks[site] >= white_level()) {
      fail("dslr: the black level {} DN at CFA site {} is not below the white level {} DN", blacks[site],
           site, white_level());
    }
  }
  first_file_number_ = prepare_folder(options_.folder);
  tracker_ = std::make_shared<ExposureTracker>("", nullptr);  // presses are watched here, not there
  worker_ = std::jthread([this](std::stop_token stop) { run(stop); });
}

SimulatedDslr::~SimulatedDslr() {
  worker_.request_stop();
  changed_.notify_all();
  worker_.join();
  if (!pending_.empty()) {
    logger("sim")->warn("dslr: stopping with {} shot(s) not yet on the card; they are lost", pending_.size());
  }
}

std::string SimulatedDslr::file_name(std::uint64_t file_number) {
  return fmt::format("IMG_{:04}.DNG", file_number);
}

std::array<double, 4> SimulatedDslr::black_levels() const {
  std::array<double, 4> levels{};
  for (std::size_t site = 0; site < levels.size(); ++site)
    levels[site] = sensor_->black_level() + options_.black_offsets[site];
  return levels;
}

double SimulatedDslr::white_level() const { return sensor_->saturation_level(); }

DslrStats SimulatedDslr::stats() const {
  const std::lock_guard lock(mutex_);
  return stats_;
}

void SimulatedDslr::record(std::span<const gpio::TimelineEntry> entries) {
  tracker_->record(entries);
  const std::lock_guard lock(mutex_);
  for (const auto& e : entries) {
    if (e.led >= 0) continue;
    if (!options_.focus_line.empty() && e.line == options_.focus_line) {
      const std::pair change{e.t_ns, e.value != 0};
      const auto at = std::upper_bound(focus_changes_.begin(), focus_changes_.end(), change.first,
                                       [](std::int64_t t, const auto& c) { return t < c.first; });
      focus_changes_.insert(at, change);
    } else if (e.line == options_.shutter_line && e.value != 0) {
      press(e.t_ns);
    }
  }
  // With no shot to render, no later press looks back before now: keep the
  // LED history short while the dome runs without pressing the shutter.
  const std::int64_t latest = tracker_->latest_ns();
  if (pending_.empty() && latest - forgot_at_ns_ > kHistoryNs) {
    tracker_->forget_before(latest - kHistoryNs);
    forgot_at_ns_ = latest;
  }
}

bool SimulatedDslr::focused_at(std::int64_t t_ns) const {
  const auto after = std::upper_bound(focus_changes_.begin(), focus_changes_.end(), t_ns,
                                      [](std::int64_t t, const auto& c) { return t < c.first; });
  return after != focus_changes_.begin() && std::prev(after)->second;
}

void SimulatedDslr::press(std::int64_t t_ns) {
  auto log = logger("sim");
  ++stats_.presses;
  if (!options_.focus_line.empty()) {
    const bool focused = focused_at(t_ns);
    // Only the state at the latest press matters from now on.
    const auto after = std::upper_bound(focus_changes_.begin(), focus_changes_.end(), t_ns - kHistoryNs,
                                        [](std::int64_t t, const auto& c) { return t < c.first; });
    if (after - focus_changes_.begin() > 1) focus_changes_.erase(focus_changes_.begin(), after - 1);
    if (!focused) {
      ++stats_.ignored_focus;
      log->info("dslr: shutter at {} ns ignored: {} (half-press) is not asserted", t_ns, options_.focus_line);
      return;
    }
  }
  if (t_ns < busy_until_ns_) {
    ++stats_.ignored_busy;
    log->info("dslr: shutter at {} ns ignored: still busy with shot {} until {} ns", t_ns, stats_.taken,
              busy_until_ns_);
    return;
  }
  while (!arrivals_.empty() && arrivals_.front() <= t_ns) arrivals_.pop_front();
  if (arrivals_.size() >= static_cast<std::size_t>(options_.buffer_shots)) {
    ++stats_.ignored_buffer;
    log->info("dslr: shutter at {} ns ignored: the buffer is full ({} shot(s) not yet on the card)", t_ns,
              arrivals_.size());
    return;
  }
  // Three draws per taken press, always, so one option does not shift another's draws.
  std::uniform_int_distribution<std::int64_t> lag(options_.lag_min_ns, options_.lag_max_ns);
  std::uniform_int_distribution<std::int64_t> delay(options_.delay_min_ns, options_.delay_max_ns);
  std::uniform_real_distribution<double> chance(0.0, 1.0);
  Shot shot{};
  shot.number = ++stats_.taken;
  shot.file_number = first_file_number_ + shot.number - 1;
  shot.start_ns = t_ns + lag(random_);
  shot.end_ns = shot.start_ns + exposure_ns_;
  shot.arrival_ns = std::max(shot.end_ns + delay(random_), last_arrival_ns_);
  const bool unlucky = chance(random_) < options_.drop_rate;
  shot.dropped = unlucky || options_.drop_shots.contains(shot.number);
  busy_until_ns_ = shot.end_ns;
  last_arrival_ns_ = shot.arrival_ns;
  arrivals_.push_back(shot.arrival_ns);
  log->debug("dslr: shot {} ({}): shutter at {} ns, exposure [{}, {}] ns, on the card at {} ns", shot.number,
             file_name(shot.file_number), t_ns, shot.start_ns, shot.end_ns, shot.arrival_ns);
  pending_.push_back(shot);
  changed_.notify_all();
}

void SimulatedDslr::run(std::stop_token stop) {
  while (!stop.stop_requested()) {
    Shot shot{};
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, stop, [this] { return !pending_.empty(); });
      if (stop.stop_requested()) return;
      shot = pending_.front();
      // Wait for the window to pass and for the chip to catch up with it.
      changed_.wait_until(lock, stop, steady_at(shot.end_ns + kWindowSettleNs), [] { return false; });
      while (!stop.stop_requested() && tracker_->latest_ns() < shot.end_ns &&
             monotonic_now_ns() < shot.end_ns + kWindowCatchUpNs) {
        changed_.wait_for(lock, stop, std::chrono::milliseconds(1), [] { return false; });
      }
      if (stop.stop_requested()) return;
    }
    const std::string name = file_name(shot.file_number);
    const fs::path path = options_.folder / name;
    auto log = logger("sim");
    std::optional<DngShot> dng;
    bool failed = false;
    if (!shot.dropped) {
      // The thread must outlive a bad shot: any error costs this file only.
      try {
        dng = develop(shot);
      } catch (const std::exception& e) {
        log->error("dslr: shot {} not written: {}: {}", shot.number, name, e.what());
        failed = true;
      }
    }
    tracker_->forget_before(shot.start_ns - kHistoryNs);
    {
      std::unique_lock lock(mutex_);
      changed_.wait_until(lock, stop, steady_at(shot.arrival_ns), [] { return false; });
      if (stop.stop_requested()) return;
    }
    bool written = false;
    if (shot.dropped) {
      log->warn("dslr: shot {} is lost: {} never reaches the card", shot.number, name);
    } else if (dng) {
      if (std::error_code error; fs::exists(path, error)) {
        log->error("dslr: shot {} not written: {} is already there", shot.number, path.string());
        failed = true;
      } else {
        try {
          write_dng(path, *dng);
          written = true;
          log->info("dslr: shot {} on the card: {}", shot.number, path.string());
        } catch (const Error& e) {
          log->error("dslr: shot {} not written: {}", shot.number, e.what());
          failed = true;
        }
      }
    }
    const std::lock_guard lock(mutex_);
    pending_.pop_front();
    stats_.written += written ? 1 : 0;
    stats_.failed += failed ? 1 : 0;
    stats_.dropped += shot.dropped ? 1 : 0;
  }
}

DngShot SimulatedDslr::develop(const Shot& shot) const {
  DngShot dng;
  dng.mosaic = mosaic_of(shot);
  dng.cfa = options_.cfa;
  dng.black_level = black_levels();
  dng.white_level = white_level();
  dng.exposure_s = exposure_us_ / 1e6;
  dng.iso = iso_;
  dng.f_number = options_.f_number;
  // The clocks' offset now, a few hundred ms after the shot: they do not drift apart that fast.
  const std::int64_t realtime_ns =
      camera::convert_timestamp_ns(shot.start_ns, camera::ClockDomain::kMonotonic,
                                   camera::ClockDomain::kRealtime) +
      options_.clock_offset_ns;
  dng.taken = std::chrono::system_clock::time_point(
      std::chrono::duration_cast<std::chrono::system_clock::duration>(std::chrono::nanoseconds(realtime_ns)));
  return dng;
}

cv::Mat SimulatedDslr::mosaic_of(const Shot& shot) const {
  const Rig& rig = world_->rig();
  std::vector<std::pair<std::size_t, double>> leds;
  for (const auto& [id, share] : tracker_->lit_shares(shot.start_ns, shot.end_ns)) {
    const auto it = led_index_.find(id);
    if (it != led_index_.end()) leds.emplace_back(it->second, share);
  }
  cv::Mat image;  // W×H: CV_64FC3 (BGR) for a coloured scene, else CV_64FC1
  if (world_->has_colour()) {
    // The LEDs as World::render weighs them: share × relative intensity.
    std::vector<LightSource> lights;
    for (const auto& [index, share] : leds)
      lights.push_back({rig.leds[index].position_mm, share * rig.leds[index].relative_intensity});
    image = world_->renderer().render_colour(lights);
  } else {
    image = world_->render(leds);
  }
  image.convertTo(image, CV_MAKETYPE(CV_64F, image.channels()));
  const int channels = image.channels();
  std::array<int, 4> channel_of_site{};
  for (std::size_t site = 0; site < 4; ++site)
    channel_of_site[site] = channels == 1 ? 0 : bgr_channel(options_.cfa[site]);

  cv::Mat radiance(image.rows * 2, image.cols * 2, CV_64FC1);
  for (int y = 0; y < image.rows; ++y) {
    const double* in = image.ptr<double>(y);
    for (int dy = 0; dy < 2; ++dy) {
      double* out = radiance.ptr<double>(2 * y + dy);
      for (int x = 0; x < image.cols; ++x) {
        for (int dx = 0; dx < 2; ++dx)
          out[2 * x + dx] = in[x * channels + channel_of_site[static_cast<std::size_t>(dy * 2 + dx)]];
      }
    }
  }
  cv::Mat mosaic = sensor_->expose(radiance, options_.seed, shot.number);
  // The per-site black offsets, clipped at the white level so saturation stays exact.
  const double white = white_level();
  for (int y = 0; y < mosaic.rows; ++y) {
    auto* row = mosaic.ptr<std::uint16_t>(y);
    for (int x = 0; x < mosaic.cols; ++x) {
      const double offset = options_.black_offsets[static_cast<std::size_t>((y % 2) * 2 + x % 2)];
      row[x] = static_cast<std::uint16_t>(std::min(row[x] + offset, white));
    }
  }
  return mosaic;
}

}  // namespace lightstage::sim
