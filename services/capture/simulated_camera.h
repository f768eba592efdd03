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

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>

#include "libs/sim/tube_scene.h"
#include "services/capture/camera_backend.h"
#include "services/capture/free_run_clock.h"
#include "services/capture/simulated_world.h"
#include "services/capture/trigger_queue.h"

namespace shapesense {

class SimulatedCamera : public CameraBackend {
 public:
  SimulatedCamera(CameraConfig config, std::shared_ptr<const SimulatedWorld> world);

  const std::string& name() const override { return config_.name; }
  // CameraError when the rig has no camera of this name.
  void Open() override;
  void Close() override;
  bool IsOpen() const override { return open_; }
  void Trigger(int64_t seq, int64_t utime) override;
  bool Grab(std::chrono::milliseconds timeout, CameraFrame* frame) override;
  CameraStats Stats() const override;

 private:
  bool NextDue(std::chrono::milliseconds timeout, QueuedTrigger* trigger, int64_t* frame_index);

  const CameraConfig config_;
  const std::shared_ptr<const SimulatedWorld> world_;
  std::atomic<bool> open_{false};
  bool ever_opened_ = false;
  size_t camera_index_ = 0;
  std::optional<SceneRenderer> renderer_;
  FreeRunClock clock_;
  int64_t next_frame_ = 0;  // free run
  TriggerQueue triggers_;
  mutable std::mutex stats_mutex_;
  CameraStats stats_;
};

}  // namespace shapesense
