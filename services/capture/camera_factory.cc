#include "services/capture/camera_factory.h"

#include <stdexcept>

#include "libs/camera/rig_yaml.h"
#include "libs/sim/scene_generators.h"
#include "runtime/file_io.h"
#include "runtime/lcm/lcm_bus.h"
#include "services/capture/aravis_camera.h"
#include "services/capture/replay_camera.h"
#include "services/capture/simulated_camera.h"
#include "services/capture/v4l2_camera.h"

namespace shapesense {

Rig LoadSimulationRig(const std::string& path) {
  if (path.empty()) return MakeSyntheticRig(SyntheticRigOptions{});
  return ParseRigYaml(ReadTextFile(path), path);
}

std::unique_ptr<CameraBackend> MakeCameraBackend(const CameraConfig& config) {
  return MakeCameraBackend(config, BackendContext{});
}

std::unique_ptr<CameraBackend> MakeCameraBackend(const CameraConfig& config,
                                                 const BackendContext& context) {
  if (const std::string error = config.Validate(); !error.empty()) {
    throw std::invalid_argument("camera '" + config.name + "': " + error);
  }
  if (config.backend == "aravis") return MakeAravisCamera(config);
  if (config.backend == "v4l2") return std::make_unique<V4l2Camera>(config, MakeLibV4l2Device());
  if (config.backend == "replay") return std::make_unique<ReplayCamera>(config);
  // Simulated: the process's world, or one of its own from the camera's rig file.
  std::shared_ptr<const SimulatedWorld> world = context.world;
  if (!world) {
    world = std::make_shared<SimulatedWorld>(LoadSimulationRig(config.device), SimulationOptions{},
                                             NowUtime());
  }
  return std::make_unique<SimulatedCamera>(config, std::move(world));
}

}  // namespace shapesense
