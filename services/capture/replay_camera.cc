#include "services/capture/replay_camera.h"

#include <algorithm>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "libs/core/error.h"
#include "runtime/file_io.h"
#include "runtime/lcm/lcm_bus.h"

namespace shapesense {
namespace fs = std::filesystem;

ReplayCamera::ReplayCamera(CameraConfig config)
    : config_(std::move(config)), clock_(config_.frame_rate) {}

void ReplayCamera::OpenDatasetFolder() {
  const fs::path frames_dir = fs::path(config_.device) / "frames";
  if (!fs::is_directory(frames_dir)) {
    throw CameraError(config_.name + ": " + frames_dir.string() +
                      ": missing folder (not a dataset)");
  }
  const std::string file = config_.name + ".png";
  for (const fs::directory_entry& entry : fs::directory_iterator(frames_dir)) {
    if (entry.is_directory() && fs::exists(entry.path() / file)) {
      frame_paths_.push_back((entry.path() / file).string());
    }
  }
  if (frame_paths_.empty()) {
    throw CameraError(config_.name + ": " + frames_dir.string() + ": no frame holds " + file);
  }
  std::sort(frame_paths_.begin(), frame_paths_.end());
}

void ReplayCamera::OpenVideo() {
  if (!video_.open(config_.device) || !video_.isOpened()) {
    throw CameraError(config_.name + ": " + config_.device + ": cannot read it as a video");
  }
}

void ReplayCamera::Open() {
  Close();
  if (fs::is_directory(config_.device)) {
    OpenDatasetFolder();
  } else if (fs::is_regular_file(config_.device)) {
    OpenVideo();
  } else {
    throw CameraError(config_.name + ": " + config_.device +
                      ": no such dataset folder or video file");
  }
  next_index_ = 0;
  clock_.Restart();
  std::lock_guard lock(stats_mutex_);
  if (ever_opened_) ++stats_.reconnects;
  ever_opened_ = true;
  open_ = true;
}

void ReplayCamera::Close() {
  open_ = false;
  frame_paths_.clear();
  video_.release();
  triggers_.Clear();
}

void ReplayCamera::Trigger(int64_t seq, int64_t utime) {
  if (open_) triggers_.Push({seq, utime});
}

bool ReplayCamera::NextDue(std::chrono::milliseconds timeout, QueuedTrigger* trigger,
                           int64_t* index) {
  if (config_.Trigger() == TriggerMode::kSoftware) {
    const std::optional<QueuedTrigger> pending = triggers_.Pop(timeout);
    if (!pending) return false;
    *trigger = *pending;
    *index = video_.isOpened() ? next_index_++ : pending->seq;
    return true;
  }
  if (!clock_.WaitNext(timeout)) return false;
  *trigger = {-1, NowUtime()};
  *index = next_index_++;
  return true;
}

cv::Mat ReplayCamera::ReadVideoFrame() {
  cv::Mat image;
  if (video_.read(image)) return image;
  if (!config_.loop) return {};
  video_.release();
  if (video_.open(config_.device) && video_.read(image)) return image;
  return {};
}

cv::Mat ReplayCamera::LoadFrame(int64_t index) {
  if (video_.isOpened()) return ReadVideoFrame();
  const auto count = static_cast<int64_t>(frame_paths_.size());
  if (index < 0 || (!config_.loop && index >= count)) return {};
  try {
    return ReadBgrImage(frame_paths_[static_cast<size_t>(index % count)]);
  } catch (const InputError&) {
    std::lock_guard lock(stats_mutex_);
    ++stats_.incomplete;  // a file that went missing or bad since Open
    return {};
  }
}

bool ReplayCamera::Grab(std::chrono::milliseconds timeout, CameraFrame* frame) {
  if (!open_) throw CameraError(config_.name + ": not open");
  QueuedTrigger trigger;
  int64_t index = 0;
  cv::Mat image;
  if (NextDue(timeout, &trigger, &index)) image = LoadFrame(index);
  if (image.empty()) {
    std::lock_guard lock(stats_mutex_);
    ++stats_.timeouts;
    return false;
  }
  if (config_.pixel_format == "Mono8") cv::cvtColor(image, image, cv::COLOR_BGR2GRAY);
  frame->image = std::move(image);
  frame->frame_id = index;
  frame->trigger_seq = trigger.seq;
  frame->trigger_utime = trigger.utime;
  frame->device_timestamp_ns = 0;
  frame->host_utime = NowUtime();
  frame->exposure_us = 0.0;
  frame->gain_db = 0.0;
  std::lock_guard lock(stats_mutex_);
  ++stats_.frames;
  return true;
}

CameraStats ReplayCamera::Stats() const {
  std::lock_guard lock(stats_mutex_);
  CameraStats stats = stats_;
  stats.missed_triggers = triggers_.Dropped();
  return stats;
}

}  // namespace shapesense
