#include "runtime/dataset.h"

#include <algorithm>
#include <cstdio>

#include "libs/camera/rig_yaml.h"
#include "libs/core/error.h"
#include "runtime/file_io.h"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

cv::Mat ReadCameraImage(const fs::path& path, const Camera& camera) {
  cv::Mat image = ReadBgrImage(path);
  if (image.cols != camera.width || image.rows != camera.height) {
    throw InputError(path.string() + ": expected " + std::to_string(camera.width) + "x" +
                     std::to_string(camera.height) + " (camera '" + camera.name + "'), got " +
                     std::to_string(image.cols) + "x" + std::to_string(image.rows));
  }
  return image;
}

std::vector<std::string> ListFrames(const fs::path& frames_dir) {
  if (!fs::is_directory(frames_dir)) throw InputError(frames_dir.string() + ": missing folder");
  std::vector<std::string> frames;
  for (const fs::directory_entry& entry : fs::directory_iterator(frames_dir)) {
    if (entry.is_directory()) frames.push_back(entry.path().filename().string());
  }
  if (frames.empty()) throw InputError(frames_dir.string() + ": no frame folders");
  std::sort(frames.begin(), frames.end());
  return frames;
}

}  // namespace

Dataset OpenDataset(const fs::path& root) {
  if (!fs::is_directory(root)) throw InputError(root.string() + ": not a dataset folder");
  Dataset dataset;
  dataset.root = root;
  const fs::path rig_path = root / "rig.yaml";
  dataset.rig = ParseRigYaml(ReadTextFile(rig_path), rig_path.string());
  for (const Camera& camera : dataset.rig.cameras) {
    dataset.backgrounds.push_back(
        ReadCameraImage(root / "background" / (camera.name + ".png"), camera));
  }
  dataset.frames = ListFrames(root / "frames");
  return dataset;
}

std::vector<cv::Mat> LoadFrame(const Dataset& dataset, const std::string& frame) {
  std::vector<cv::Mat> images;
  for (const Camera& camera : dataset.rig.cameras) {
    images.push_back(
        ReadCameraImage(dataset.root / "frames" / frame / (camera.name + ".png"), camera));
  }
  return images;
}

void WriteDatasetHeader(const fs::path& root, const Rig& rig,
                        const std::vector<cv::Mat>& backgrounds) {
  fs::create_directories(root / "background");
  fs::create_directories(root / "frames");
  WriteFileAtomically(root / "rig.yaml", FormatRigYaml(rig));
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    WritePng(root / "background" / (rig.cameras[i].name + ".png"), backgrounds.at(i));
  }
}

void WriteFrame(const fs::path& root, const Rig& rig, const std::string& frame,
                const std::vector<cv::Mat>& images) {
  const fs::path dir = root / "frames" / frame;
  fs::create_directories(dir);
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    WritePng(dir / (rig.cameras[i].name + ".png"), images.at(i));
  }
}

std::string FrameName(int index) {
  char name[16];
  std::snprintf(name, sizeof(name), "%06d", index);
  return name;
}

}  // namespace shapesense
