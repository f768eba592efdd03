#include "services/capture/simulated_camera.h"

#include <opencv2/imgproc.hpp>

#include "runtime/lcm/lcm_bus.h"

namespace shapesense {

SimulatedCamera::SimulatedCamera(CameraConfig config, std::shared_ptr<const SimulatedWorld> world)
    : config_(std::move(config)), world_(std::move(world)), clock_(config_.frame_rate) {}

void SimulatedCamera::Open() {
  Close();
  const Rig& rig = world_->rig();
  const Camera* camera = rig.Find(config_.name);
  if (camera == nullptr) {
    std::string names;
    for (const Camera& c : rig.cameras) names += (names.empty() ? "" : ", ") + c.name;
    throw CameraError(config_.name + ": the simulated rig has no such camera (it has " + names +
                      ")");
  }
  camera_index_ = static_cast<size_t>(camera - rig.cameras.data());
  if (!renderer_) {
    Rig own = rig;
    own.cameras = {*camera};
    renderer_.emplace(own);
  }
  next_frame_ = 0;
  clock_.Restart();
  std::lock_guard lock(stats_mutex_);
  if (ever_opened_) ++stats_.reconnects;
  ever_opened_ = true;
  open_ = true;
}

void SimulatedCamera::Close() {
  open_ = false;
  triggers_.Clear();
}

void SimulatedCamera::Trigger(int64_t seq, int64_t utime) {
  if (open_) triggers_.Push({seq, utime});
}

bool SimulatedCamera::NextDue(std::chrono::milliseconds timeout, QueuedTrigger* trigger,
                              int64_t* frame_index) {
  if (config_.Trigger() == TriggerMode::kSoftware) {
    const std::optional<QueuedTrigger> pending = triggers_.Pop(timeout);
    if (!pending) return false;
    *trigger = *pending;
    *frame_index = pending->seq;
    return true;
  }
  if (!clock_.WaitNext(timeout)) return false;
  *trigger = {-1, NowUtime()};
  *frame_index = next_frame_++;
  return true;
}

bool SimulatedCamera::Grab(std::chrono::milliseconds timeout, CameraFrame* frame) {
  if (!open_) throw CameraError(config_.name + ": not open");
  QueuedTrigger trigger;
  int64_t index = 0;
  if (!NextDue(timeout, &trigger, &index)) {
    std::lock_guard lock(stats_mutex_);
    ++stats_.timeouts;
    return false;
  }
  const TubeScene scene = world_->SceneAtUtime(trigger.utime);
  RenderedView view =
      renderer_->Render(scene, world_->render(), world_->ViewSeed(index, camera_index_))[0];
  cv::Mat image = world_->options().show_manipulator ? view.image : view.background;
  if (config_.pixel_format == "Mono8") cv::cvtColor(image, image, cv::COLOR_BGR2GRAY);
  frame->image = std::move(image);
  frame->frame_id = index;
  frame->trigger_seq = trigger.seq;
  frame->trigger_utime = trigger.utime;
  frame->device_timestamp_ns = 0;
  frame->host_utime = NowUtime();
  frame->exposure_us = config_.exposure_us;
  frame->gain_db = config_.gain_db;
  std::lock_guard lock(stats_mutex_);
  ++stats_.frames;
  return true;
}

CameraStats SimulatedCamera::Stats() const {
  std::lock_guard lock(stats_mutex_);
  CameraStats stats = stats_;
  stats.missed_triggers = triggers_.Dropped();
  return stats;
}

}  // namespace shapesense
