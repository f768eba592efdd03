#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "runtime/sensing_pipeline.h"

namespace shapesense {

struct OfflineArgs {
  std::filesystem::path dataset;
  std::filesystem::path out;         // JSON lines, one per frame; OUT.config.yaml beside it:
                                     // the effective options, version and time
  std::optional<double> voxel_size;  // mm; overrides the config
  std::filesystem::path config;      // pipeline YAML (config/pipeline.yaml); empty: defaults
  std::filesystem::path overlays;    // folder for overlay PNGs; empty: none
  bool progress = true;              // progress bar on a terminal
};

struct OfflineSummary {
  int frames = 0;
  int measured = 0;
  StageTimes mean_times;  // over measured frames
  double table_build_s = 0.0;
};

// Called after each frame with its images (empty when they could not be read)
// and result; lets the demo score frames against the truth.
using FrameObserver = std::function<void(
    const std::string& frame, const std::vector<cv::Mat>& images, const FrameResult& result)>;

// Runs the sensing chain over an image-folder dataset and writes one JSON line
// per frame. Throws InputError (before writing anything) on a malformed
// dataset or config; a frame that cannot be measured gets an error line.
OfflineSummary RunOffline(const OfflineArgs& args, std::ostream& log,
                          const FrameObserver& observer = {});

// Registers `shapesense offline`.
void AddOfflineCommand(CLI::App& app);

// Overlay picture of one frame: the camera views tiled, over the orthogonal views.
cv::Mat MakeFrameOverlay(const Rig& rig, const std::vector<cv::Mat>& images,
                         const FrameResult& result, const Polyline* truth);

}  // namespace shapesense
