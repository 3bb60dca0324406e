#pragma once
// A dome to work with: its rig, its controller and its camera, each opened by
// URI with every backend this program knows (hw cameras, the sim: camera), and
// the controller checked to run the same rig. `capture`, `camera` and the
// station open their dome here.

#include "lightstage/common/camera.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/host/controller/controller_client.hpp"

#include <filesystem>
#include <memory>
#include <string>

namespace lightstage::pipeline {

struct DomeConnection {
  Rig rig;
  std::unique_ptr<ControllerClient> controller;
  std::unique_ptr<camera::Camera> camera;
};

// Registers the camera backends (once), opens the camera, connects to the
// controller. Throws InputError naming --rig when the controller runs another rig.
DomeConnection connect_dome(const std::filesystem::path& rig_path, const std::string& controller_uri,
                            const std::string& camera_uri);

}  // namespace lightstage::pipeline
