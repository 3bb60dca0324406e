#include "lightstage/pipeline/dome_connection.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/hw/cameras.hpp"
#include "lightstage/sim/camera/sim_camera.hpp"

namespace lightstage::pipeline {

DomeConnection connect_dome(const std::filesystem::path& rig_path, const std::string& controller_uri,
                            const std::string& camera_uri) {
  DomeConnection dome;
  dome.rig = load_rig(rig_path);
  hw::register_hw_cameras();
  sim::register_sim_camera();
  dome.camera = camera::open_camera_uri(camera_uri);
  dome.controller = connect_controller(controller_uri);
  if (dome.controller->info().rig_name() != dome.rig.name) {
    fail("--rig '{}' is rig '{}', but the controller runs rig '{}'", rig_path.string(), dome.rig.name,
         dome.controller->info().rig_name());
  }
  return dome;
}

}  // namespace lightstage::pipeline
