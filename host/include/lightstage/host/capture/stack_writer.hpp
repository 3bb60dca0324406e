#pragma once
// Writes a capture's stack folder while it is taken: each frame's image as it
// lands (atomic file + rename), then filenames.txt, the light files and
// manifest.json rewritten (io::write_stack), so the folder is a loadable stack
// at every moment and an interrupted capture keeps every frame it took. The
// manifest's "capture" section holds the plan (LED order, exposures, darks)
// and which frames are done; resume() reads it back (io/stack_manifest).

#include "lightstage/common/camera.hpp"
#include "lightstage/common/image_stack.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/host/capture/capture_plan.hpp"
#include "lightstage/host/capture/capture_runner.hpp"
#include "lightstage/host/capture/response_curve.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace lightstage {

// What an interrupted capture had planned, by LED id (empty: nothing yet).
struct PreviousPlan {
  std::map<int, double> exposure_us;
  std::map<int, std::vector<double>> bracket_exposure_us;
};

// How the frames are taken, recorded in the manifest.
struct CaptureSetup {
  double gain = 1;
  bool closed_loop = false;
  bool hardware_trigger = false;
  camera::CameraInfo camera;
  std::string controller_firmware;
  std::string controller_rig;
  std::optional<double> fixed_exposure_us;  // --exposure-us; unset = automatic
};

class CaptureStackWriter {
 public:
  // `response`, when given, linearises frames and darks (written as float PFM); it must outlive the writer.
  CaptureStackWriter(const Rig& rig, std::filesystem::path out, const InverseResponse* response);

  // --resume: reads out/manifest.json when there is one, checks it was planned
  // for `led_ids` with the options' bracket stops, fixed or automatic
  // exposure (--exposure-us) and dark frames, and keeps the frames it lists
  // (their images read back) and its darks. Returns the exposures it planned.
  // Throws InputError naming the manifest and what does not fit.
  PreviousPlan resume(const std::vector<int>& led_ids, const CaptureOptions& asked);

  // The plan the frames are added by; call before anything below. Darks the
  // resumed manifest lists are matched to the plan's exposures.
  void set_plan(const CapturePlan& plan, const CaptureSetup& setup);

  std::size_t frame_count() const { return frames_.size(); }
  // Per planned frame: whether it is in the stack already.
  std::vector<bool> done() const;
  bool has_dark(std::size_t exposure) const;

  // Averages `frames` (all at the plan's exposure `exposure`) into its dark
  // frame and writes it as dark_<exposure>us.png (.pfm when linearised).
  void add_dark(std::size_t exposure, const std::vector<cv::Mat>& frames);
  // Writes planned frame `frame` from its one take.
  void add_frame(std::size_t frame, const Take& take);
  // Merges planned frame `frame`'s bracket (hdr_merge.hpp) into one float
  // frame per exposure-second and writes it.
  void add_hdr_frame(std::size_t frame, const std::vector<Take>& takes);

  // Rewrites the stack's index files and manifest for the frames written so far.
  void write_index(bool complete);

 private:
  struct Dark {
    std::string file;
    double mean = 0;
    cv::Mat image;  // as written: 16-bit DN or linearised float; read back lazily after a resume
  };
  cv::Mat dark_image(std::size_t exposure);
  void write_image(const std::string& name, const cv::Mat& image) const;

  const Rig& rig_;
  std::filesystem::path out_;
  const InverseResponse* response_;
  CapturePlan plan_;
  CaptureSetup setup_;
  std::vector<std::pair<double, Dark>>
      resumed_darks_;                       // by exposure, until set_plan matches them to the plan's
  std::vector<std::optional<Dark>> darks_;  // by the plan's exposure index
  std::map<std::size_t, Frame> frames_;     // by planned frame: frames in the stack
  std::map<std::size_t, nlohmann::json> frame_extra_;
};

}  // namespace lightstage
