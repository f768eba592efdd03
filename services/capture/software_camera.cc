#include "services/capture/software_camera.h"

#include <opencv2/imgproc.hpp>

#include "runtime/lcm/lcm_bus.h"

namespace shapesense {

SoftwareCamera::SoftwareCamera(CameraConfig config, bool has_exposure)
    : config_(std::move(config)), has_exposure_(has_exposure), clock_(config_.frame_rate) {}

void SoftwareCamera::Open() {
  Close();
  OpenSource();
  next_index_ = 0;
  clock_.Restart();
  std::lock_guard lock(stats_mutex_);
  if (ever_opened_) ++stats_.reconnects;
  ever_opened_ = true;
  open_ = true;
}

void SoftwareCamera::Close() {
  open_ = false;
  CloseSource();
  triggers_.Clear();
}

void SoftwareCamera::Trigger(int64_t seq, int64_t utime) {
  if (open_) triggers_.Push({seq, utime});
}

bool SoftwareCamera::NextDue(std::chrono::milliseconds timeout, QueuedTrigger* trigger,
                             int64_t* index) {
  if (config_.Trigger() == TriggerMode::kSoftware) {
    const std::optional<QueuedTrigger> pending = triggers_.Pop(timeout);
    if (!pending) return false;
    *trigger = *pending;
    *index = CountsOwnFrames() ? next_index_++ : pending->seq;
    return true;
  }
  if (!clock_.WaitNext(timeout)) return false;
  *trigger = {-1, NowUtime()};
  *index = next_index_++;
  return true;
}

bool SoftwareCamera::Grab(std::chrono::milliseconds timeout, CameraFrame* frame) {
  if (!open_) throw CameraError(config_.name + ": not open");
  QueuedTrigger trigger;
  int64_t index = 0;
  cv::Mat image;
  if (NextDue(timeout, &trigger, &index)) image = MakeImage(index, trigger.utime);
  const bool made = !image.empty();
  if (made) Stamp(std::move(image), trigger, index, frame);  // converts: outside the lock
  std::lock_guard lock(stats_mutex_);
  ++(made ? stats_.frames : stats_.timeouts);
  return made;
}

void SoftwareCamera::Stamp(cv::Mat image, const QueuedTrigger& trigger, int64_t index,
                           CameraFrame* frame) const {
  if (config_.pixel_format == "Mono8") cv::cvtColor(image, image, cv::COLOR_BGR2GRAY);
  frame->image = std::move(image);
  frame->frame_id = index;
  frame->trigger_seq = trigger.seq;
  frame->trigger_utime = trigger.utime;
  frame->device_timestamp_ns = 0;
  frame->host_utime = NowUtime();
  frame->exposure_us = has_exposure_ ? config_.exposure_us : 0.0;
  frame->gain_db = has_exposure_ ? config_.gain_db : 0.0;
}

void SoftwareCamera::CountIncomplete() {
  std::lock_guard lock(stats_mutex_);
  ++stats_.incomplete;
}

CameraStats SoftwareCamera::Stats() const {
  std::lock_guard lock(stats_mutex_);
  CameraStats stats = stats_;
  stats.missed_triggers = triggers_.Dropped();
  return stats;
}

}  // namespace shapesense
