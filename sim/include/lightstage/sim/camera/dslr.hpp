#pragma once
// A stills camera on the dome's remote-release port, as lightstage-sim's
// physical world: it watches the virtual gpiochip's timeline for the shutter
// (full press) line and writes one raw file per shot into a folder, the way a
// DSLR fills its card or a tethering folder. The host matches files to LED
// steps; this camera gives it the real camera's trouble to cope with.
//
// Timing model (all in the chip's CLOCK_MONOTONIC stamps, from the firmware):
//   - an active shutter edge at t is ignored (and logged) while the camera is
//     busy with the previous shot (from its press to the end of its exposure),
//     while `buffer_shots` shots are exposed but not yet on the card, or, with
//     a focus line, while the half-press is not asserted at t;
//   - otherwise the press is taken: shot n (counting from 1) exposes during
//     [t + lag, t + lag + exposure], lag drawn uniformly from [lag_min, lag_max];
//   - its file IMG_<NNNN>.DNG arrives a card delay after the exposure, drawn
//     uniformly from [delay_min, delay_max], never before the previous file
//     (cards write in order); a dropped shot (listed, or drawn with drop_rate)
//     writes nothing but keeps its number, like a lost transfer.
// All draws come from one generator seeded with `seed`, three per taken press
// in press order, so a run is reproducible from its timeline alone.
//
// The image: the World's W×H rendering (colour when the scene has one, else
// grey) lit by each LED's share of the exposure window, spread over a 2W×2H
// Bayer mosaic (each 2×2 block carries that pixel's R, G, G, B, per `cfa`) and
// exposed through the sensor model at 2W×2H, so each site has its own noise.
// A half-size decode (R, mean of the Gs, B per block) gives back the image the
// `sim:` camera would have given at the same exposure, gain and black level.
// Levels: the DNG's black at site s is black_level + black_offsets[s] (the
// offset is added to the site's DN), its white level the sensor's saturation
// level; a site is clipped at the white level, so saturation reads exactly
// white whatever the offset.
//
// EXIF: Make "Lightstage", Model "Simulated DSLR", ExposureTime, ISO =
// 100 × gain, FNumber, DateTimeOriginal + SubSec = the start of the exposure
// on CLOCK_REALTIME (converted when the shot is rendered) plus
// `clock_offset_ns`, as a camera clock is never quite right.

#include "lightstage/sim/camera/exposure_tracker.hpp"
#include "lightstage/sim/dng_writer.hpp"
#include "lightstage/sim/gpio/timeline.hpp"
#include "lightstage/sim/simulate.hpp"

#include <array>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <span>
#include <string>
#include <thread>
#include <vector>

namespace lightstage::sim {

struct DslrOptions {
  std::filesystem::path folder;          // where the files land; created if missing
  std::string shutter_line = "TRIGGER";  // the chip's name for the full press (ChipLayout::display_name)
  std::string focus_line;                // the half-press; "" = the camera fires without one
  // The dials: default the rig camera's exposure_us and 100 × the sensor's gain.
  std::optional<double> exposure_us;
  std::optional<double> iso;
  double f_number = 8;
  std::int64_t lag_min_ns = 40'000'000, lag_max_ns = 120'000'000;       // shutter lag
  std::int64_t delay_min_ns = 150'000'000, delay_max_ns = 900'000'000;  // end of exposure to file
  int buffer_shots = 16;               // shots exposed but not yet on the card, at most
  std::set<std::uint64_t> drop_shots;  // shot numbers (counting from 1) whose file is lost
  double drop_rate = 0;                // chance, in [0, 1), that any other shot's file is lost
  std::int64_t clock_offset_ns = 0;    // the camera clock's error, added to EXIF times
  // Black level, DN: default the sensor's when it has one, else 512 (a raw file
  // keeps the read noise around black instead of clipping it at 0).
  std::optional<double> black_level;
  std::array<double, 4> black_offsets = {0, 2, 4, 6};  // added per CFA site, same order as `cfa`
  std::array<char, 4> cfa = {'R', 'G', 'G', 'B'};
  std::uint64_t seed = 1;  // lag, delay, drop draws; shot n's noise draws from (seed, n)

  // Throws InputError naming the field, its value and the rule broken.
  void check() const;
};

// What happened to the presses so far (for logs and tests).
struct DslrStats {
  std::uint64_t presses = 0;         // active shutter edges seen
  std::uint64_t taken = 0;           // presses that exposed a shot
  std::uint64_t ignored_busy = 0;    // during the previous shot's lag or exposure
  std::uint64_t ignored_buffer = 0;  // with the buffer full
  std::uint64_t ignored_focus = 0;   // without the half-press
  std::uint64_t dropped = 0;         // taken, but their file never arrived
  std::uint64_t written = 0;         // files on the card
  std::uint64_t failed = 0;          // files that could not be written (logged)
};

class SimulatedDslr final : public gpio::TimelineSink {
 public:
  // `sensor` is the sensor the `sim:` camera uses (noise, response, bit depth);
  // the DSLR sets its exposure, gain and black level from `options`. Creates
  // the folder and numbers on after the highest IMG_<NNNN> file in it. Throws
  // InputError for bad options, a folder path that is a file or cannot be
  // created, or a sensor the options make invalid.
  SimulatedDslr(std::shared_ptr<const World> world, SensorOptions sensor, DslrOptions options);
  ~SimulatedDslr() override;  // shots not yet on the card are lost (logged)
  SimulatedDslr(const SimulatedDslr&) = delete;
  SimulatedDslr& operator=(const SimulatedDslr&) = delete;

  // Add to the virtual chip. Quick: presses are decided here, shots rendered
  // and written by the camera's own thread.
  void record(std::span<const gpio::TimelineEntry> entries) override;

  DslrStats stats() const;
  // The file name shot `file_number` gets: IMG_0001.DNG.
  static std::string file_name(std::uint64_t file_number);
  // The number of this run's first file: after the highest IMG_<NNNN> present at start.
  std::uint64_t first_file_number() const { return first_file_number_; }
  double exposure_us() const { return exposure_us_; }
  double iso() const { return iso_; }
  // Per CFA site, DN.
  std::array<double, 4> black_levels() const;
  double white_level() const;

 private:
  struct Shot {
    std::uint64_t number;       // taken presses, counting from 1
    std::uint64_t file_number;  // IMG_<file_number>.DNG
    std::int64_t start_ns, end_ns, arrival_ns;
    bool dropped;
  };

  void press(std::int64_t t_ns);             // caller holds mutex_
  bool focused_at(std::int64_t t_ns) const;  // caller holds mutex_
  void run(std::stop_token stop);
  DngShot develop(const Shot& shot) const;  // the file's contents: render, expose, EXIF
  cv::Mat mosaic_of(const Shot& shot) const;

  std::shared_ptr<const World> world_;
  DslrOptions options_;
  std::unique_ptr<Sensor> sensor_;
  double exposure_us_ = 0, iso_ = 0;
  std::int64_t exposure_ns_ = 0;
  std::uint64_t first_file_number_ = 1;
  std::map<int, std::size_t> led_index_;  // LED id -> rig index
  std::shared_ptr<ExposureTracker> tracker_;

  mutable std::mutex mutex_;
  std::condition_variable_any changed_;
  std::mt19937_64 random_;
  std::vector<std::pair<std::int64_t, bool>> focus_changes_;  // (t, asserted), time order
  std::int64_t busy_until_ns_ = 0;
  std::int64_t last_arrival_ns_ = 0;
  std::int64_t forgot_at_ns_ = 0;      // when the LED history was last cut while idle
  std::deque<std::int64_t> arrivals_;  // of shots still in the buffer at the last press
  std::deque<Shot> pending_;
  DslrStats stats_;
  std::jthread worker_;  // last: starts after everything it uses
};

}  // namespace lightstage::sim
