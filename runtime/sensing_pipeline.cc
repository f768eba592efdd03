#include "runtime/sensing_pipeline.h"

#include <chrono>

#include "libs/core/error.h"

namespace shapesense {
namespace {

using Clock = std::chrono::steady_clock;

double MillisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace

namespace {

void CheckBackgrounds(const Rig& rig, const std::vector<cv::Mat>& backgrounds) {
  if (backgrounds.size() != rig.cameras.size()) {
    throw InputError("expected one background per camera (" + std::to_string(rig.cameras.size()) +
                     "), got " + std::to_string(backgrounds.size()));
  }
  for (size_t i = 0; i < backgrounds.size(); ++i) {
    const Camera& camera = rig.cameras[i];
    if (backgrounds[i].type() != CV_8UC3 || backgrounds[i].cols != camera.width ||
        backgrounds[i].rows != camera.height) {
      throw InputError("background of camera '" + camera.name + "': expected 8-bit BGR of " +
                       std::to_string(camera.width) + "x" + std::to_string(camera.height));
    }
  }
}

}  // namespace

SilhouetteStage::SilhouetteStage(const Rig& rig, std::vector<cv::Mat> backgrounds,
                                 const SilhouetteOptions& options)
    : backgrounds_((CheckBackgrounds(rig, backgrounds), std::move(backgrounds))),
      extractor_(options) {}

std::string PipelineOptions::Validate() const {
  for (const auto& [section, error] :
       {std::pair{"silhouette.", silhouette.Validate()}, std::pair{"carving.", carving.Validate()},
        std::pair{"shape.", shape.Validate()}}) {
    if (!error.empty()) return section + error;
  }
  return {};
}

SensingPipeline::SensingPipeline(const Rig& rig, const PipelineOptions& options,
                                 std::vector<cv::Mat> backgrounds,
                                 const ProgressCallback& table_progress)
    : rig_(rig),
      options_(options),
      silhouettes_(rig, std::move(backgrounds), options.silhouette),
      carver_(rig, options.carving, table_progress),
      estimator_(rig, options.shape) {}

void SensingPipeline::Process(const std::vector<cv::Mat>& images, FrameResult* result) const {
  if (images.size() != rig_.cameras.size()) {
    result->shape = ShapeEstimate{};
    result->shape.error = "expected " + std::to_string(rig_.cameras.size()) + " images, got " +
                          std::to_string(images.size());
    return;
  }
  result->silhouettes.resize(images.size());
  auto start = Clock::now();
  for (size_t i = 0; i < images.size(); ++i) {
    silhouettes_.Extract(i, images[i], &result->silhouettes[i]);
  }
  result->times.silhouette_ms = MillisecondsSince(start);

  start = Clock::now();
  if (options_.full_scan) {
    carver_.CarveFullScan(result->silhouettes, &result->cloud);
  } else {
    carver_.CarveHierarchical(result->silhouettes, &result->cloud);
  }
  result->times.carving_ms = MillisecondsSince(start);

  start = Clock::now();
  result->shape = estimator_.Estimate(result->cloud, result->silhouettes);
  result->times.shape_ms = MillisecondsSince(start);
}

}  // namespace shapesense
