#pragma once
// The virtual camera of lightstage-sim, served over sim_camera.proto. It sees
// the scene lit by exactly the LEDs the virtual gpiochip recorded as on during
// its exposure window, each weighted by the share of the window it was on, and
// exposes that through the sensor model (exposure, gain, noise, quantisation).
//
// Trigger modes: hardware (an exposure starts `delay` after each active edge
// of the rig's trigger line), software (an exposure starts at the request),
// free-run (exposures back to back). A frame is rendered once its window has
// passed and the chip has seen every change up to the window's end.

#include "lightstage/sim/camera/exposure_tracker.hpp"
#include "lightstage/sim/gpio/service_host.hpp"
#include "lightstage/sim/simulate.hpp"

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>

namespace lightstage {
class MessageChannel;
}

namespace lightstage::sim {

struct CameraServiceOptions {
  std::string trigger_line = "TRIGGER";     // the chip's name for the trigger (ChipLayout::display_name)
  std::int64_t trigger_delay_ns = 100'000;  // trigger edge to start of exposure
  // Called when the exposure changes, so the emulated strobe matches it.
  std::function<void(std::int64_t exposure_ns)> on_exposure_change;
  std::uint64_t seed = 1;  // noise: frame n draws from (seed, n)
  // Fault: exposures (counting from 1) whose frame is lost on the way, as a
  // camera or USB link loses one; the sequence number still advances.
  std::set<std::uint64_t> drop_frames;
};

class CameraService final : public ConnectionService {
 public:
  // `world` renders the scene for the rig the chip was built from.
  CameraService(std::shared_ptr<const World> world, SensorOptions sensor, CameraServiceOptions options);
  ~CameraService() override;
  CameraService(const CameraService&) = delete;
  CameraService& operator=(const CameraService&) = delete;

  // The timeline sink to add to the virtual chip.
  std::shared_ptr<ExposureTracker> tracker() const { return tracker_; }

  void serve(std::unique_ptr<ByteLink> link, std::stop_token stop) override;
  std::string name() const override { return "camera"; }

  // Frames delivered so far (for logs and tests).
  std::uint64_t frames_sent() const;

 private:
  struct Exposure {
    std::int64_t start_ns, end_ns;
  };
  enum class Mode { kFreeRun, kSoftware, kHardware };

  void on_trigger(std::int64_t t_ns);
  void queue_exposure(std::int64_t start_ns);
  void run_exposures(std::stop_token stop);
  void deliver(const Exposure& exposure);

  std::shared_ptr<const World> world_;
  SensorOptions sensor_options_;
  CameraServiceOptions options_;
  std::shared_ptr<ExposureTracker> tracker_;
  std::map<int, std::size_t> led_index_;  // LED id -> rig index

  mutable std::mutex mutex_;
  std::condition_variable_any changed_;
  Mode mode_ = Mode::kHardware;
  bool streaming_ = false;
  double exposure_us_, gain_;
  int roi_x_ = 0, roi_y_ = 0, roi_width_ = 0, roi_height_ = 0;
  std::deque<Exposure> pending_;
  std::int64_t busy_until_ns_ = 0;  // triggers during an exposure are ignored, as a sensor would
  std::uint64_t sequence_ = 0;
  std::shared_ptr<MessageChannel> client_;
  std::jthread worker_;  // last: starts after everything it uses
};

}  // namespace lightstage::sim
