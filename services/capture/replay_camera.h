#pragma once

// Replays recorded images as a camera: an image-folder dataset
// (DIR/frames/<NNNNNN>/<camera>.png, the offline command's layout, see
// runtime/dataset.h) or a video file (anything cv::VideoCapture reads).
//
// Free run: one frame every 1 / frame_rate s. Software trigger: one frame per
// Trigger(); from a dataset, frame-set `seq` is frame folder seq (modulo the
// count when looping), so every camera of a set replays the same folder even
// after one of them was reopened; a video has no such index and advances one
// frame per trigger. Without `loop` the camera delivers nothing after the end.

#include <atomic>
#include <chrono>
#include <mutex>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <string>
#include <vector>

#include "services/capture/camera_backend.h"
#include "services/capture/free_run_clock.h"
#include "services/capture/trigger_queue.h"

namespace shapesense {

class ReplayCamera : public CameraBackend {
 public:
  explicit ReplayCamera(CameraConfig config);

  const std::string& name() const override { return config_.name; }
  void Open() override;
  void Close() override;
  bool IsOpen() const override { return open_; }
  void Trigger(int64_t seq, int64_t utime) override;
  bool Grab(std::chrono::milliseconds timeout, CameraFrame* frame) override;
  CameraStats Stats() const override;

  // Frames of this camera in the dataset; 0 for a video.
  size_t FrameCount() const { return frame_paths_.size(); }

 private:
  void OpenDatasetFolder();
  void OpenVideo();
  // The next frame to deliver and its trigger; false when none is due within `timeout`.
  bool NextDue(std::chrono::milliseconds timeout, QueuedTrigger* trigger, int64_t* index);
  cv::Mat LoadFrame(int64_t index);
  cv::Mat ReadVideoFrame();

  const CameraConfig config_;
  std::atomic<bool> open_{false};
  bool ever_opened_ = false;
  std::vector<std::string> frame_paths_;  // dataset frames of this camera, in order
  cv::VideoCapture video_;
  int64_t next_index_ = 0;  // free run, and video in any mode
  FreeRunClock clock_;
  TriggerQueue triggers_;
  mutable std::mutex stats_mutex_;
  CameraStats stats_;
};

}  // namespace shapesense
