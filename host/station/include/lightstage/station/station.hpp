#pragma once
// The operator's station: a dome (its rig, controller and camera), the data
// folder it fills and the one long job it runs at a time, as the page sees
// them. The HTTP layer (station_server.hpp) only maps requests onto this.
//
// DATA holds stacks/NAME (captures), calibrations/NAME, results/NAME (solve
// and report), surfaces/NAME (its depth and mesh), exports/ (RTI files), audit.log and .station/ (the capture
// requests a resume repeats, the simulated dome's logs). Nothing already in a folder is overwritten: a name
// in use is refused.
//
// The dome: one thread at a time works with the controller and camera. A job
// that needs them (capture, test sequence) holds them until it ends; LEDs lit
// by hand are refused meanwhile. Darkening never waits for that: it goes to
// the controller at once (its protocol takes requests from any thread). The
// controller's watchdog darkens the dome whenever this process stops feeding
// it (killed, hung), and the station darkens it when the operator who lit
// LEDs by hand goes away.

#include "lightstage/pipeline/dome_connection.hpp"
#include "lightstage/station/simulated_bench.hpp"
#include "lightstage/station/station_job.hpp"
#include "lightstage/station/station_requests.hpp"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace lightstage::station {

struct StationOptions {
  std::filesystem::path rig;
  std::string controller_uri;
  std::string camera_uri;
  std::filesystem::path data;
  // The station starts the simulated dome's programs itself (controller and camera URIs unused).
  std::optional<SimulatedBenchOptions> simulated;
};

// A camera frame at one LED, for focusing and exposing: the picture and its figures.
struct Preview {
  std::string png;       // 8-bit PNG of the frame
  nlohmann::json stats;  // histogram (64 bins of full scale), clipped share, sharpness, size
};

class Station {
 public:
  explicit Station(StationOptions options);
  ~Station();  // stops the job, darkens the dome

  const std::filesystem::path& data() const { return options_.data; }

  nlohmann::json status();           // dome, LEDs lit, job, simulated placement
  nlohmann::json rig_json() const;   // the LEDs' ids, names and directions, for the map
  nlohmann::json data_json() const;  // stacks, calibrations, results
  std::vector<std::string> methods() const;

  void set_leds(const LedsRequest& request);  // Refused(409) while a job holds the dome
  // Every LED off at once, whatever runs: the running sequence is aborted (a
  // capture pauses keeping its frames, a test sequence stops). Throws when the
  // controller cannot be told (its watchdog darkens a dome nobody feeds).
  void dark();
  bool lit_by_hand() const;
  Preview preview(const PreviewRequest& request);
  void place(const std::string& what);  // simulated only: the object or a chrome sphere position

  // A chrome-sphere stack's outline as the calibration would find it (its
  // mask.png, else detected): {"circle": {x_px, y_px, radius_px} | null,
  // "error", "width", "height"}; its picture (the maximum over its frames,
  // brightened to show a dark sphere's rim) as PNG.
  nlohmann::json sphere(const std::string& stack) const;
  std::string sphere_png(const std::string& stack) const;
  // The outline the operator drew, written as the stack's mask.png (a disk),
  // which the calibration then uses; refused over a mask.png the station did not write.
  nlohmann::json set_sphere(const std::string& stack, const SphereCircle& circle);
  // Removes the outline drawn here (the calibration then detects the sphere again).
  nlohmann::json forget_sphere(const std::string& stack);

  nlohmann::json start_test_sequence(const TestSequenceRequest& request);
  nlohmann::json start_capture(const CaptureRequest& request);
  nlohmann::json resume_capture(const std::string& name);
  nlohmann::json start_calibration(const CalibrationRequest& request);
  nlohmann::json start_solve(const SolveRequest& request);
  // An RTI file of a result's stack, exports/RESULT.ptm (PTM) or .rti (HSH), for RTIViewer and the like.
  nlohmann::json start_export(const std::string& result, const std::string& format);
  // Asks the running job to stop at its next safe point (a capture keeps its
  // frames, a solve's partial folders go). An abort also forgets a capture's
  // plan: it is not resumed. Refused(409) for calibrations and exports, which
  // end by themselves.
  void stop_job(bool abort = false);
  nlohmann::json job_json() const;
  // Waits for the job to end (tests, shutdown).
  void wait_job();

 private:
  using Work = StationJob::Work;
  // Starts `work` as the job; Refused(409) while another runs.
  nlohmann::json start_job(const std::string& kind, nlohmann::json request, bool stoppable, Work work);
  // The connected dome (connecting when needed); dome_mutex_ held by the caller.
  std::shared_ptr<pipeline::DomeConnection> dome();
  std::shared_ptr<pipeline::DomeConnection> connected() const;  // or null; any thread
  void drop_dome(const std::string& why);                       // after a failure: reconnect next time
  void abort_sequence();  // the controller's running sequence, if any, ends dark
  bool may_reconnect();   // dome_mutex_ held
  nlohmann::json capture_work(StationJob& job, const CaptureRequest& request, bool resume);
  nlohmann::json calibration_work(StationJob& job, const CalibrationRequest& request);
  nlohmann::json solve_work(StationJob& job, const SolveRequest& request);
  nlohmann::json solve_stages(StationJob& job, const SolveRequest& request);
  nlohmann::json test_sequence_work(StationJob& job, const TestSequenceRequest& request);
  void set_lit(std::vector<std::pair<std::uint32_t, float>> lit, bool by_hand);
  std::filesystem::path folder(const char* kind, const std::string& name) const;
  std::filesystem::path existing_stack(const std::string& name) const;  // Refused(404) when there is none

  StationOptions options_;
  Rig rig_;
  std::unique_ptr<SimulatedBench> bench_;

  std::mutex dome_mutex_;          // the controller and camera: one user at a time
  mutable std::mutex link_mutex_;  // dome_ itself (dark() reads it without dome_mutex_)
  std::shared_ptr<pipeline::DomeConnection> dome_;
  std::chrono::steady_clock::time_point last_connect_attempt_{};

  mutable std::mutex state_mutex_;  // what status() reports
  std::string dome_error_;
  nlohmann::json controller_ = nullptr;  // the last status read
  std::vector<std::pair<std::uint32_t, float>> lit_;
  bool lit_by_hand_ = false;

  mutable std::mutex job_mutex_;
  int next_job_id_ = 1;
  std::shared_ptr<StationJob> job_;
  std::atomic<bool> abort_{false};     // the running job was aborted, not paused
  std::atomic<bool> darkened_{false};  // dark() cut the running job's sequence short
};

}  // namespace lightstage::station
