#include "services/capture/replay_camera.h"

#include <algorithm>
#include <filesystem>

#include "libs/core/error.h"
#include "runtime/file_io.h"

namespace shapesense {
namespace fs = std::filesystem;

ReplayCamera::ReplayCamera(CameraConfig config)
    : SoftwareCamera(std::move(config), /*has_exposure=*/false) {}

void ReplayCamera::OpenDatasetFolder() {
  const fs::path frames_dir = fs::path(config().device) / "frames";
  if (!fs::is_directory(frames_dir)) {
    throw CameraError(config().name + ": " + frames_dir.string() +
                      ": missing folder (not a dataset)");
  }
  const std::string file = config().name + ".png";
  for (const fs::directory_entry& entry : fs::directory_iterator(frames_dir)) {
    if (entry.is_directory() && fs::exists(entry.path() / file)) {
      frame_paths_.push_back((entry.path() / file).string());
    }
  }
  if (frame_paths_.empty()) {
    throw CameraError(config().name + ": " + frames_dir.string() + ": no frame holds " + file);
  }
  std::sort(frame_paths_.begin(), frame_paths_.end());
}

void ReplayCamera::OpenVideo() {
  if (!video_.open(config().device) || !video_.isOpened()) {
    throw CameraError(config().name + ": " + config().device + ": cannot read it as a video");
  }
}

void ReplayCamera::OpenSource() {
  if (fs::is_directory(config().device)) {
    OpenDatasetFolder();
  } else if (fs::is_regular_file(config().device)) {
    OpenVideo();
  } else {
    throw CameraError(config().name + ": " + config().device +
                      ": no such dataset folder or video file");
  }
}

void ReplayCamera::CloseSource() {
  frame_paths_.clear();
  video_.release();
}

cv::Mat ReplayCamera::ReadVideoFrame() {
  cv::Mat image;
  if (video_.read(image)) return image;
  if (!config().loop) return {};
  video_.release();
  if (video_.open(config().device) && video_.read(image)) return image;
  return {};
}

cv::Mat ReplayCamera::MakeImage(int64_t index, int64_t /*trigger_utime*/) {
  if (video_.isOpened()) return ReadVideoFrame();
  const auto count = static_cast<int64_t>(frame_paths_.size());
  if (index < 0 || (!config().loop && index >= count)) return {};
  try {
    return ReadBgrImage(frame_paths_[static_cast<size_t>(index % count)]);
  } catch (const InputError&) {
    CountIncomplete();  // a file that went missing or bad since Open
    return {};
  }
}

}  // namespace shapesense
