#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "libs/camera/camera.h"

namespace shapesense {

// An image-folder dataset (docs/dataset.md):
//   DIR/rig.yaml                          the rig, OpenCV FileStorage YAML
//   DIR/background/<camera>.png           one background per camera
//   DIR/frames/<NNNNNN>/<camera>.png      one folder per frame-set
struct Dataset {
  std::filesystem::path root;
  Rig rig;
  std::vector<cv::Mat> backgrounds;  // in rig order
  std::vector<std::string> frames;   // frame folder names, in order
};

// Opens and checks the whole layout before any frame is read; a malformed
// dataset is an InputError naming the file and what is wrong.
Dataset OpenDataset(const std::filesystem::path& root);

// The images of one frame-set in rig order; InputError naming the image when
// one is missing, unreadable or of the wrong size.
std::vector<cv::Mat> LoadFrame(const Dataset& dataset, const std::string& frame);

// Writes a rig and its backgrounds in the dataset layout (used by the demo
// and the tests); frames are added with WriteFrame.
void WriteDatasetHeader(const std::filesystem::path& root, const Rig& rig,
                        const std::vector<cv::Mat>& backgrounds);
void WriteFrame(const std::filesystem::path& root, const Rig& rig, const std::string& frame,
                const std::vector<cv::Mat>& images);

// Frame folder name of index i: six digits, as the layout expects.
std::string FrameName(int index);

}  // namespace shapesense
