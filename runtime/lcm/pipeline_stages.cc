#include "runtime/lcm/pipeline_stages.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <stdexcept>

#include "libs/camera/rig_yaml.h"
#include "libs/core/error.h"
#include "runtime/file_io.h"
#include "runtime/lcm/image_codec.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/lcm/shape_message.h"
#include "runtime/lcm/silhouette_message.h"
#include "runtime/lcm/stage_times.h"
#include "runtime/lcm/voxel_cloud_message.h"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;

int64_t MicrosecondsSince(Clock::time_point start) {
  return std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - start).count();
}

std::optional<ConfigurationSetup> CheckedConfiguration(std::optional<ConfigurationSetup> setup) {
  if (!setup) return setup;
  for (const std::string& error : {setup->geometry.Validate(), setup->options.Validate()}) {
    if (!error.empty()) throw std::invalid_argument("configuration: " + error);
  }
  return setup;
}

// The "silhouette" stage of a set: from the first preparation that began
// once the set was complete (all of them, when none did) to the last end.
stage_time_t SilhouetteStageTime(const std::vector<PreparedView>& views, int64_t complete_utime) {
  int64_t start = std::numeric_limits<int64_t>::max();
  int64_t earliest = start;
  int64_t end = 0;
  for (const PreparedView& view : views) {
    if (view.start_utime >= complete_utime) start = std::min(start, view.start_utime);
    earliest = std::min(earliest, view.start_utime);
    end = std::max(end, view.end_utime);
  }
  if (start > end) start = earliest;
  return MakeStageTime("silhouette", end - start, end);
}

bool SameFrameSet(const voxel_cloud_t& voxels, const SilhouetteSet& silhouettes) {
  return voxels.trigger_seq == silhouettes.trigger_seq &&
         voxels.trigger_utime == silhouettes.trigger_utime;
}

}  // namespace

RigSetup LoadRigSetup(const fs::path& rig_file, const fs::path& background_folder) {
  RigSetup setup;
  setup.rig = ParseRigYaml(ReadTextFile(rig_file), rig_file.string());
  if (background_folder.empty()) return setup;
  for (const Camera& camera : setup.rig.cameras) {
    const fs::path path = background_folder / (camera.name + ".png");
    cv::Mat image = ReadBgrImage(path);
    if (image.cols != camera.width || image.rows != camera.height) {
      throw InputError(path.string() + ": expected " + std::to_string(camera.width) + "x" +
                       std::to_string(camera.height) + " (camera '" + camera.name + "'), got " +
                       std::to_string(image.cols) + "x" + std::to_string(image.rows));
    }
    setup.backgrounds.push_back(std::move(image));
  }
  return setup;
}

std::vector<std::string> CameraNames(const Rig& rig) {
  std::vector<std::string> names;
  for (const Camera& camera : rig.cameras) names.push_back(camera.name);
  return names;
}

std::string DecodeImage(const image_t& image, const Camera& camera, cv::Mat* bgr) {
  return DecodeImage(image, image.data, camera, bgr);
}

std::string DecodeImage(const image_t& image, std::span<const uint8_t> bytes, const Camera& camera,
                        cv::Mat* bgr) {
  if (image.width != camera.width || image.height != camera.height) {
    return camera.name + ": expected " + std::to_string(camera.width) + "x" +
           std::to_string(camera.height) + " (the rig's), got " + std::to_string(image.width) +
           "x" + std::to_string(image.height);
  }
  return ImageMessageToBgr(image, bytes, bgr, ImageCopy::kViewWhenPossible);
}

std::vector<stage_time_t> FrameSetStageTimes(const FrameSet& set) {
  std::vector<stage_time_t> stages;
  int64_t transport_us = 0;
  for (size_t i = 0; i < set.images.size(); ++i) {
    const image_t& image = set.images[i];
    for (const stage_time_t& stage : image.stage_times) MergeStageTime(stage, &stages);
    if (image.header.utime > 0 && i < set.receive_utime.size()) {
      transport_us = std::max(transport_us, set.receive_utime[i] - image.header.utime);
    }
  }
  stages.push_back(MakeStageTime("transport", transport_us, set.complete_utime));
  return stages;
}

CarvingStage::CarvingStage(const Rig& rig, std::vector<cv::Mat> backgrounds,
                           const SilhouetteOptions& silhouette, const CarvingOptions& carving,
                           const ProgressCallback& table_progress)
    : rig_(rig),
      silhouettes_(rig, std::move(backgrounds), silhouette),
      carver_(rig, carving, table_progress) {}

std::string CarvingStage::PrepareView(size_t camera, const image_t& image, PreparedView* view,
                                      CompactScratch* scratch) const {
  return PrepareView(camera, image, image.data, view, scratch);
}

std::string CarvingStage::PrepareView(size_t camera, const image_t& image,
                                      std::span<const uint8_t> bytes, PreparedView* view,
                                      CompactScratch* scratch) const {
  view->start_utime = NowUtime();
  view->end_utime = 0;
  view->error.clear();
  if (camera >= rig_.cameras.size()) {
    view->error = "no camera " + std::to_string(camera) + " in the rig";
    return view->error;
  }
  cv::Mat bgr;
  if (std::string error = DecodeImage(image, bytes, rig_.cameras[camera], &bgr); !error.empty()) {
    view->error = error;
    return error;
  }
  silhouettes_.Extract(camera, bgr, &view->silhouette);
  Compact(view->silhouette, &view->compact, scratch);
  view->end_utime = NowUtime();
  return {};
}

std::string CarvingStage::Carve(const FrameSet& set, std::vector<PreparedView>* views,
                                CarvingOutput* out) const {
  const size_t n = rig_.cameras.size();
  if (set.images.size() != n || views->size() != n) {
    return "expected " + std::to_string(n) + " images, got " + std::to_string(set.images.size());
  }
  for (size_t k = 0; k < n; ++k) {
    PreparedView& view = (*views)[k];
    if (!view.error.empty()) return view.error;
    if (view.end_utime > 0) continue;
    if (set.images[k].data.empty()) {
      return set.images[k].camera + ": its silhouette was not kept, and its image holds no bytes";
    }
    if (std::string error = PrepareView(k, set.images[k], &view, &out->compact_scratch);
        !error.empty()) {
      return error;
    }
  }
  out->silhouettes.resize(n);
  out->compact.views.resize(n);
  for (size_t k = 0; k < n; ++k) {
    std::swap(out->silhouettes[k], (*views)[k].silhouette);
    std::swap(out->compact.views[k], (*views)[k].compact);
  }

  const auto start = Clock::now();
  carver_.CarveHierarchical(out->silhouettes, &out->cloud);
  const int64_t carving_us = MicrosecondsSince(start);

  out->message = VoxelCloudToMessage(out->cloud);
  out->message.trigger_seq = set.trigger_seq;
  out->message.trigger_utime = set.trigger_utime;
  out->message.stage_times = FrameSetStageTimes(set);
  out->message.stage_times.push_back(SilhouetteStageTime(*views, set.complete_utime));
  out->message.stage_times.push_back(MakeStageTime("carving", carving_us, NowUtime()));
  out->message.num_stage_times = static_cast<int32_t>(out->message.stage_times.size());

  out->compact.trigger_seq = set.trigger_seq;
  out->compact.trigger_utime = set.trigger_utime;
  SilhouettesToMessage(rig_, out->compact, &out->silhouettes_message);
  return {};
}

std::string CarvingStage::Process(const FrameSet& set, CarvingOutput* out) const {
  out->views.resize(set.images.size());
  for (PreparedView& view : out->views) {
    view.end_utime = 0;
    view.error.clear();
  }
  return Carve(set, &out->views, out);
}

ShapeStage::ShapeStage(const Rig& rig, const ShapeOptions& shape,
                       std::optional<ConfigurationSetup> configuration)
    : rig_(rig),
      wants_silhouettes_(shape.refine_with_silhouettes),
      estimator_(rig, shape),
      configuration_(CheckedConfiguration(std::move(configuration))) {}

std::string ShapeStage::ExpandSilhouettes(const voxel_cloud_t& voxels, const SilhouetteSet* set,
                                          ShapeOutput* out) const {
  if (set == nullptr) return "none";
  if (!SameFrameSet(voxels, *set)) return "of another frame-set";
  if (set->views.size() != rig_.cameras.size()) {
    return "expected " + std::to_string(rig_.cameras.size()) + " views, got " +
           std::to_string(set->views.size());
  }
  out->silhouettes.resize(set->views.size());
  out->tape_runs = 0;
  for (size_t k = 0; k < set->views.size(); ++k) {
    Expand(set->views[k], &out->silhouettes[k]);
    out->tape_runs += set->views[k].markers.size();
  }
  return {};
}

void ShapeStage::SenseConfigurationOf(ShapeOutput* out) const {
  out->configuration = ConfigurationMeasurement{};
  if (!configuration_) return;
  const ShapeEstimate& estimate = out->estimate;
  if (!estimate.valid) {
    out->configuration.reason = "no shape";
    return;
  }
  if (out->refined && out->tape_runs == 0) {
    // Said apart from "a band hidden": no band can be measured until the
    // colour is set right, and it is the silhouettes' config that is wrong.
    out->configuration.reason =
        "no camera sees any tape: the tape colour of the silhouettes (silhouette.tape: hue_deg, "
        "min_saturation, min_value) matches no pixel of the tube, or every band is out of view; "
        "`shapesense tape-colour` learns it from an image";
    return;
  }
  out->configuration =
      SenseConfiguration({estimate.centerline, estimate.arc_length, estimate.marker_arc_length},
                         configuration_->geometry, configuration_->options);
}

std::string ShapeStage::Process(const voxel_cloud_t& voxels, const SilhouetteSet* silhouettes,
                                ShapeOutput* out) const {
  if (std::string error = VoxelCloudFromMessage(voxels, &out->cloud); !error.empty()) return error;
  const auto start = Clock::now();
  out->warning.clear();
  out->refined = false;
  if (wants_silhouettes_) {
    const std::string error = ExpandSilhouettes(voxels, silhouettes, out);
    out->refined = error.empty();
    if (!out->refined) out->warning = "silhouettes: " + error + "; shape not refined";
  }
  static const std::vector<Silhouette> kNone;
  out->estimate = estimator_.Estimate(out->cloud, out->refined ? out->silhouettes : kNone);
  SenseConfigurationOf(out);
  const int64_t shape_us = MicrosecondsSince(start);

  out->message = ShapeToMessage(out->estimate);
  if (out->configuration.valid) {
    SetMessageConfiguration(out->configuration.q, out->configuration.rms_residual, &out->message);
  }
  out->message.trigger_seq = voxels.trigger_seq;
  out->message.trigger_utime = voxels.trigger_utime;
  out->message.stage_times = voxels.stage_times;
  out->message.stage_times.push_back(MakeStageTime("shape", shape_us, NowUtime()));
  out->message.num_stage_times = static_cast<int32_t>(out->message.stage_times.size());
  return {};
}

}  // namespace shapesense
