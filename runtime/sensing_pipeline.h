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

// The first stage of every sensing chain (offline here, live in the carving
// service, replay): each camera's image against its own background.
class SilhouetteStage {
 public:
  // Throws InputError unless there is one 8-bit BGR background per camera
  // of the rig, of its camera's size.
  SilhouetteStage(const Rig& rig, std::vector<cv::Mat> backgrounds,
                  const SilhouetteOptions& options);

  // The silhouette in `image` (8-bit BGR of its size) of the rig's camera
  // `camera` (< the number of cameras). Thread-safe.
  void Extract(size_t camera, const cv::Mat& image, Silhouette* out) const {
    extractor_.Extract(image, backgrounds_[camera], out);
  }

 private:
  std::vector<cv::Mat> backgrounds_;
  SilhouetteExtractor extractor_;
};

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
  SilhouetteStage silhouettes_;
  Carver carver_;
  ShapeEstimator estimator_;
};

}  // namespace shapesense
