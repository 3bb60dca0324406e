#include "lightstage/pipeline/dome_connection.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/printable.hpp"
#include "lightstage/common/rig_fingerprint.hpp"
#include "lightstage/host/capture/file_camera.hpp"
#include "lightstage/hw/cameras.hpp"
#include "lightstage/sim/camera/sim_camera.hpp"

namespace lightstage::pipeline {

void check_same_rig(const Rig& rig, const std::filesystem::path& rig_path, const proto::Info& info) {
  if (info.rig_name() != rig.name) {
    fail("--rig '{}' is rig '{}', but the controller runs rig '{}'", rig_path.string(), printable(rig.name),
         printable(info.rig_name()));
  }
  // A controller from before fingerprints sends none: the name is all there is to compare.
  if (info.rig_fingerprint().empty()) return;
  const std::string ours = rig_fingerprint(rig);
  if (info.rig_fingerprint() != ours) {
    fail(
        "--rig '{}' and the controller's rig are both named '{}' but differ (fingerprint {} here, {} on the "
        "controller): give both the same rig file",
        rig_path.string(), printable(rig.name), ours, printable(info.rig_fingerprint()));
  }
}

DomeConnection connect_dome(const std::filesystem::path& rig_path, const std::string& controller_uri,
                            const std::string& camera_uri) {
  DomeConnection dome;
  dome.rig = load_rig(rig_path);
  hw::register_hw_cameras();
  sim::register_sim_camera();
  register_file_cameras();
  dome.camera = camera::open_camera_uri(camera_uri);
  dome.controller = connect_controller(controller_uri);
  check_same_rig(dome.rig, rig_path, dome.controller->info());
  return dome;
}

}  // namespace lightstage::pipeline
