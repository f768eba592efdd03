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

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <string>
#include <vector>

#include "services/capture/software_camera.h"

namespace shapesense {

class ReplayCamera : public SoftwareCamera {
 public:
  explicit ReplayCamera(CameraConfig config);

  // Frames of this camera in the dataset; 0 for a video.
  size_t FrameCount() const { return frame_paths_.size(); }

 private:
  void OpenSource() override;
  void CloseSource() override;
  bool CountsOwnFrames() const override { return video_.isOpened(); }
  cv::Mat MakeImage(int64_t index, int64_t trigger_utime) override;
  void OpenDatasetFolder();
  void OpenVideo();
  cv::Mat ReadVideoFrame();

  std::vector<std::string> frame_paths_;  // dataset frames of this camera, in order
  cv::VideoCapture video_;
};

}  // namespace shapesense
