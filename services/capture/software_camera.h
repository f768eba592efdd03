#pragma once

// What the cameras made in software (replay, simulated) share: software
// triggers wait in a queue, free run follows a clock, the frame is counted
// and stamped, Mono8 is made from the source's colour image. A subclass only
// opens its source and makes the image of a frame index.

#include <atomic>
#include <chrono>
#include <mutex>
#include <opencv2/core.hpp>
#include <string>

#include "services/capture/camera_backend.h"
#include "services/capture/free_run_clock.h"
#include "services/capture/trigger_queue.h"

namespace shapesense {

class SoftwareCamera : public CameraBackend {
 public:
  const std::string& name() const override { return config_.name; }
  // Opens the source (CameraError when it cannot) and restarts the frame count.
  void Open() override;
  void Close() override;
  bool IsOpen() const override { return open_; }
  void Trigger(int64_t seq, int64_t utime) override;
  bool Grab(std::chrono::milliseconds timeout, CameraFrame* frame) override;
  CameraStats Stats() const override;

 protected:
  // `has_exposure`: the source knows the exposure and gain of its images
  // (the configured ones); else they are reported as 0 (unknown).
  SoftwareCamera(CameraConfig config, bool has_exposure);

  const CameraConfig& config() const { return config_; }
  // A frame the source could not make for a reason worth counting (a file
  // gone bad since Open), besides the timeout it causes.
  void CountIncomplete();

 private:
  virtual void OpenSource() = 0;
  virtual void CloseSource() = 0;
  // True when the source has no frame index of its own (a video) and counts
  // its frames even under software trigger; else frame-set `seq` is frame `seq`.
  virtual bool CountsOwnFrames() const { return false; }
  // The BGR image of frame `index` triggered at `trigger_utime`; empty when none.
  virtual cv::Mat MakeImage(int64_t index, int64_t trigger_utime) = 0;

  // The next frame to make and its trigger; false when none is due within `timeout`.
  bool NextDue(std::chrono::milliseconds timeout, QueuedTrigger* trigger, int64_t* index);
  void Stamp(cv::Mat image, const QueuedTrigger& trigger, int64_t index, CameraFrame* frame) const;

  const CameraConfig config_;
  const bool has_exposure_;
  std::atomic<bool> open_{false};
  bool ever_opened_ = false;
  int64_t next_index_ = 0;  // free run, and sources that count their own frames
  FreeRunClock clock_;
  TriggerQueue triggers_;
  mutable std::mutex stats_mutex_;
  CameraStats stats_;
};

}  // namespace shapesense
