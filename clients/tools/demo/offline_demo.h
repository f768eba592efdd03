#pragma once

// `shapesense demo --offline`: the chain in one process on a rendered
// sequence, with overlay pictures; no LCM, no network.
#include <cstdint>
#include <filesystem>
#include <ostream>

#include "libs/evaluation/shape_error.h"
#include "runtime/sensing_pipeline.h"

namespace shapesense {

struct OfflineDemoArgs {
  std::filesystem::path out = "demo-output";
  int frames = 16;
  uint32_t seed = 7;
  double voxel_size = 1.0;  // mm
  bool progress = true;
};

struct OfflineDemoReport {
  ShapeErrorSummary accuracy;
  StageTimes mean_times;
  double table_build_s = 0.0;
};

// Renders a synthetic sequence (arcs bending to 150°, then S-curves) on a
// virtual three-camera rig into an image-folder dataset, runs the offline
// chain on it, scores every frame against the ground truth, and writes
// out/dataset/, out/shapes.jsonl, out/overlays/*.png and out/report.json.
OfflineDemoReport RunOfflineDemo(const OfflineDemoArgs& args, std::ostream& log);

}  // namespace shapesense
