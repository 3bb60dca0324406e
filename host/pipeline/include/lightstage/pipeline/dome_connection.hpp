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

// Throws InputError naming `rig_path` when the controller's Info names another
// rig, or the same name with another content fingerprint (rig_fingerprint.hpp).
void check_same_rig(const Rig& rig, const std::filesystem::path& rig_path, const proto::Info& info);

// Registers the camera backends (once), opens the camera, connects to the
// controller. Throws InputError naming --rig when the controller runs another rig
// (check_same_rig).
DomeConnection connect_dome(const std::filesystem::path& rig_path, const std::string& controller_uri,
                            const std::string& camera_uri);

}  // namespace lightstage::pipeline
