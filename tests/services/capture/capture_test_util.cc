#include "tests/services/capture/capture_test_util.h"

#include <unistd.h>

#include <atomic>
#include <random>

#include "libs/sim/scene_generators.h"
#include "runtime/dataset.h"
#include "runtime/lcm/image_codec.h"

namespace shapesense::testing {
namespace fs = std::filesystem;

TempDir::TempDir(const std::string& tag) {
  static std::atomic<int> counter{0};
  path_ = fs::temp_directory_path() /
          ("shapesense_" + tag + "_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
  fs::remove_all(path_);
  fs::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ignored;
  fs::remove_all(path_, ignored);
}

cv::Mat RandomImage(int width, int height, uint32_t seed) {
  cv::Mat image(height, width, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

Rig SmallRig(int cameras, int width, int height) {
  SyntheticRigOptions options;
  options.num_cameras = cameras;
  options.image_width = width;
  options.image_height = height;
  options.focal_px = 700.0 * width / 640.0;
  return MakeSyntheticRig(options);
}

std::vector<std::vector<cv::Mat>> WriteRandomDataset(const fs::path& root, const Rig& rig,
                                                     int frames, uint32_t seed) {
  std::vector<cv::Mat> backgrounds;
  for (const Camera& camera : rig.cameras)
    backgrounds.push_back(RandomImage(camera.width, camera.height, seed));
  WriteDatasetHeader(root, rig, backgrounds);
  std::vector<std::vector<cv::Mat>> images;
  for (int f = 0; f < frames; ++f) {
    std::vector<cv::Mat> set;
    for (size_t c = 0; c < rig.cameras.size(); ++c) {
      set.push_back(RandomImage(rig.cameras[c].width, rig.cameras[c].height,
                                seed * 7919 + static_cast<uint32_t>(f * 31 + c)));
    }
    WriteFrame(root, rig, FrameName(f), set);
    images.push_back(set);
  }
  return images;
}

CameraConfig ReplayConfig(const std::string& name, const std::string& device,
                          const std::string& trigger) {
  CameraConfig config;
  config.name = name;
  config.backend = "replay";
  config.device = device;
  config.trigger = trigger;
  return config;
}

bool SameImage(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

cv::Mat DecodedImage(const image_t& message) {
  cv::Mat image;
  const std::string error = message.pixel_format == image_t::PIXEL_MONO8
                                ? ImageMessageToMono(message, &image)
                                : ImageMessageToBgr(message, &image);
  return error.empty() ? image : cv::Mat();
}

}  // namespace shapesense::testing
