#pragma once

#include <memory>
#include <string>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/carving/carver.h"
#include "libs/centerline/shape_estimator.h"
#include "libs/silhouette/silhouette.h"

namespace shapesense {

// The options of the whole sensing chain, one section per stage
// (config/pipeline.yaml documents every key).
struct PipelineOptions {
  SilhouetteOptions silhouette;
  CarvingOptions carving;
  ShapeOptions shape;
  // Carve with the full lookup-table scan instead of the hierarchical search
  // (same result, for comparison).
  bool full_scan = false;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("silhouette", silhouette, "silhouette extraction");
    visit("carving", carving, "voxel carving");
    visit("shape", shape, "centreline and markers");
    visit("full_scan", full_scan,
          "carve by the full lookup-table scan (baseline) instead of the hierarchy");
  }
  std::string Validate() const;
};

// Wall-clock time of each stage of one frame-set, ms.
struct StageTimes {
  double silhouette_ms = 0.0;
  double carving_ms = 0.0;
  double shape_ms = 0.0;
  double Total() const { return silhouette_ms + carving_ms + shape_ms; }
};

struct FrameResult {
  std::vector<Silhouette> silhouettes;
  VoxelCloud cloud;
  ShapeEstimate shape;
  StageTimes times;
};

// Throws InputError unless there is one 8-bit BGR background per camera of
// the rig, of its camera's size (every chain that extracts silhouettes).
void CheckBackgrounds(const Rig& rig, const std::vector<cv::Mat>& backgrounds);

// Silhouettes → carving → shape for one rig, timing each stage. Owns the
// lookup table, so build it once per rig.
class SensingPipeline {
 public:
  // Throws InputError on options or backgrounds that do not fit the rig.
  SensingPipeline(const Rig& rig, const PipelineOptions& options, std::vector<cv::Mat> backgrounds,
                  const ProgressCallback& table_progress = {});

  // `images` in the order of rig.cameras, 8-bit BGR. A frame that cannot be
  // measured comes back with shape.valid false and the reason in shape.error.
  void Process(const std::vector<cv::Mat>& images, FrameResult* result) const;

  const Rig& rig() const { return rig_; }
  const Carver& carver() const { return carver_; }

 private:
  Rig rig_;
  PipelineOptions options_;
  std::vector<cv::Mat> backgrounds_;
  SilhouetteExtractor extractor_;
  Carver carver_;
  ShapeEstimator estimator_;
};

}  // namespace shapesense
