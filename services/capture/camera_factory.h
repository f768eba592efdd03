#pragma once

#include <memory>
#include <string>

#include "libs/camera/camera.h"
#include "services/capture/camera_backend.h"
#include "services/capture/simulated_world.h"

namespace shapesense {

// What the cameras of one process share.
struct BackendContext {
  // The world the simulated cameras look at. Null: each simulated camera
  // makes its own from its `device` (a rig file; empty: the synthetic rig)
  // with the default SimulationOptions and t = 0 now.
  std::shared_ptr<const SimulatedWorld> world;
};

// The backend `config.backend` names, not yet opened. Throws
// std::invalid_argument on a config that fails Validate(), InputError on an
// unreadable rig file (simulated without a context world).
std::unique_ptr<CameraBackend> MakeCameraBackend(const CameraConfig& config);
std::unique_ptr<CameraBackend> MakeCameraBackend(const CameraConfig& config,
                                                 const BackendContext& context);

// The rig of a simulation: the rig file at `path`, or with an empty path the
// default synthetic rig (MakeSyntheticRig: cam0, cam1, cam2, 640x480).
// InputError naming the file and key when it is malformed.
Rig LoadSimulationRig(const std::string& path);

}  // namespace shapesense
