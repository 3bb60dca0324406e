#pragma once
// Which file a stills camera wrote for which sequence step (frame_matcher.hpp
// does this for cameras stamping frames on the host's clocks).
//
// A DSLR stamps its shots (EXIF DateTimeOriginal + SubSecTimeOriginal) on its
// own clock, off the controller's by an unknown, steady amount (seconds, a
// time zone), and starts each exposure anywhere from 0 to the rig's shutter
// lag after its trigger. So pairs (file, step) are consistent when every
// file's stamp minus its step's trigger falls in one window [c, c + lag +
// resolution]. The controller spaces steps further apart than the lag (it
// keeps each LED lit for lag + exposure), so for a given c each file has at
// most one step. Files come in the order they were taken (a card writes in
// order); none arrives before its exposure ended, nor (with a timeout) later
// than the arrival timeout after.
//
// Every window some pair opens is tried; the one matching most files wins.
// When another matching as large exists (a file missing from evenly spaced
// steps and no clock offset known yet), no step is matched: retaking the
// batch is better than a file filed under the wrong LED. A known offset (from
// an earlier batch: a camera clock drifts by seconds a day, not in minutes)
// settles such ties: the matching whose mean stamp-minus-trigger is nearest.

#include "lightstage/host/capture/frame_matcher.hpp"

#include <cstdint>
#include <optional>
#include <vector>

namespace lightstage {

struct ShotTiming {
  std::int64_t stamp_ns = 0;       // the camera's clock
  std::int64_t resolution_ns = 0;  // the stamp's step (1 ms with sub-seconds, 1 s without); 0 = no stamp
  std::int64_t arrived_ns = 0;     // CLOCK_MONOTONIC, like the steps' triggers
};

struct ShotMatchOptions {
  std::int64_t max_lag_ns = 0;          // trigger to start of exposure, at most
  std::int64_t arrival_timeout_ns = 0;  // end of exposure to the file's arrival, at most; 0 = unbounded
  // An earlier batch's ShotMatch::clock_offset_ns.
  std::optional<std::int64_t> clock_offset_ns;
};

struct ShotMatch : FrameMatch {
  bool ambiguous = false;  // files left unmatched because two matchings tie
  // The matched files' mean stamp minus trigger (the camera clock's offset
  // plus the mean shutter lag), when files were matched by stamp.
  std::optional<std::int64_t> clock_offset_ns;
};

ShotMatch match_shots(const std::vector<StepTiming>& steps, const std::vector<ShotTiming>& shots,
                      const ShotMatchOptions& options);

}  // namespace lightstage
