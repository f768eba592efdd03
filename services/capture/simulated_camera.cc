#include "services/capture/simulated_camera.h"

namespace shapesense {

SimulatedCamera::SimulatedCamera(CameraConfig config, std::shared_ptr<const SimulatedWorld> world)
    : SoftwareCamera(std::move(config), /*has_exposure=*/true), world_(std::move(world)) {}

void SimulatedCamera::OpenSource() {
  const Rig& rig = world_->rig();
  const Camera* camera = rig.Find(config().name);
  if (camera == nullptr) {
    std::string names;
    for (const Camera& c : rig.cameras) names += (names.empty() ? "" : ", ") + c.name;
    throw CameraError(config().name + ": the simulated rig has no such camera (it has " + names +
                      ")");
  }
  camera_index_ = static_cast<size_t>(camera - rig.cameras.data());
  if (!renderer_) {
    Rig own = rig;
    own.cameras = {*camera};
    renderer_.emplace(own);
  }
}

cv::Mat SimulatedCamera::MakeImage(int64_t index, int64_t trigger_utime) {
  const TubeScene scene = world_->SceneAtUtime(trigger_utime);
  RenderedView view =
      renderer_->Render(scene, world_->render(), world_->ViewSeed(index, camera_index_))[0];
  return world_->options().show_manipulator ? view.image : view.background;
}

}  // namespace shapesense
