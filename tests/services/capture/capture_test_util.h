#pragma once

// Shared by the capture tests: temporary folders, small datasets and rigs.

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "libs/camera/camera.h"
#include "services/capture/camera_backend.h"
#include "shapesense/image_t.hpp"

namespace shapesense::testing {

// A fresh folder under the system's temporary folder, removed at the end.
class TempDir {
 public:
  explicit TempDir(const std::string& tag);
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

cv::Mat RandomImage(int width, int height, uint32_t seed);

// A synthetic rig of `cameras` cameras (cam0, ...) of width × height.
Rig SmallRig(int cameras, int width = 96, int height = 72);

// Writes `frames` frame-sets of random images for `rig` in the dataset layout;
// returns images[frame][camera].
std::vector<std::vector<cv::Mat>> WriteRandomDataset(const std::filesystem::path& root,
                                                     const Rig& rig, int frames, uint32_t seed = 1);

CameraConfig ReplayConfig(const std::string& name, const std::string& device,
                          const std::string& trigger = "software");

bool SameImage(const cv::Mat& a, const cv::Mat& b);

// The pixels of an image message as published: MONO8 as grey, else BGR;
// empty when the message does not decode.
cv::Mat DecodedImage(const image_t& message);

}  // namespace shapesense::testing
