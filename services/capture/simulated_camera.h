#pragma once

// A camera of the virtual rig, rendered in process: the view of camera
// `name` of the world's rig, of the world's scene at the trigger time.
//
// Each camera renders only its own view with its own SceneRenderer (a rig
// of that one camera), so the grab threads of several cameras render in
// parallel. The image of frame-set `seq` triggered at `utime` is exactly
//   SceneRenderer({camera}).Render(world.SceneAtUtime(utime), world.render(),
//                                  world.ViewSeed(seq, index of camera in the rig))[0].image
// (converted to grey for Mono8; `.background` without the manipulator). In free run `seq` is the
// camera's own frame counter and the trigger time is when the frame fell due.

#include <memory>
#include <optional>

#include "libs/sim/tube_scene.h"
#include "services/capture/simulated_world.h"
#include "services/capture/software_camera.h"

namespace shapesense {

class SimulatedCamera : public SoftwareCamera {
 public:
  SimulatedCamera(CameraConfig config, std::shared_ptr<const SimulatedWorld> world);

 private:
  // CameraError when the rig has no camera of this name.
  void OpenSource() override;
  void CloseSource() override {}
  cv::Mat MakeImage(int64_t index, int64_t trigger_utime) override;

  const std::shared_ptr<const SimulatedWorld> world_;
  size_t camera_index_ = 0;
  std::optional<SceneRenderer> renderer_;
};

}  // namespace shapesense
