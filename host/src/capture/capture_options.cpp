#include "lightstage/host/capture/capture_options.hpp"

#include "lightstage/common/error.hpp"

#include <cmath>
#include <set>

namespace lightstage {

void CaptureOptions::check() const {
  if (out.empty()) fail("capture: --out is required");
  if (exposure_us && !(*exposure_us > 0))
    fail("capture: --exposure-us must be positive, got {}", *exposure_us);
  if (!(auto_target > 0 && auto_target < 1))
    fail("capture: --auto-target must be in (0, 1), got {}", auto_target);
  if (!(auto_percentile > 0 && auto_percentile <= 1)) {
    fail("capture: --auto-percentile must be in (0, 1], got {}", auto_percentile);
  }
  if (gain && !(*gain > 0)) fail("capture: --gain must be positive, got {}", *gain);
  if (dark_frames < 0) fail("capture: --dark-frames must be >= 0, got {}", dark_frames);
  if (max_retakes < 0) fail("capture: --max-retakes must be >= 0, got {}", max_retakes);
  if (loop != "open" && loop != "closed" && loop != "auto") {
    fail("capture: --loop must be open, closed or auto, got '{}'", loop);
  }
  if (!bracket_stops.empty()) {
    if (bracket_stops.size() < 2)
      fail("capture: --bracket needs at least 2 stops, got {}", bracket_stops.size());
    std::set<double> seen;
    for (const double stop : bracket_stops) {
      if (!(std::abs(stop) <= 16)) fail("capture: --bracket stop {} is not within [-16, 16]", stop);
      if (!seen.insert(stop).second) fail("capture: --bracket stop {} is given twice", stop);
    }
  }
}

}  // namespace lightstage
