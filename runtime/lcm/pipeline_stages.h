#pragma once

// The sensing chain cut at the LCM channels: frame-set → voxel cloud and
// compact silhouettes (CarvingStage, in the carving service), and voxel
// cloud + compact silhouettes → shape (ShapeStage, in the shape service).
// `shapesense replay` runs the same two stages on a recorded log, so replay
// reproduces the live shapes exactly.
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/carving/carver.h"
#include "libs/centerline/shape_estimator.h"
#include "libs/mechanics/configuration_sensing.h"
#include "libs/silhouette/compact_silhouette.h"
#include "libs/silhouette/silhouette.h"
#include "runtime/config_file.h"
#include "runtime/lcm/frame_set_assembler.h"
#include "runtime/lcm/silhouette_message.h"
#include "runtime/sensing_pipeline.h"
#include "shapesense/shape_t.hpp"
#include "shapesense/silhouettes_t.hpp"
#include "shapesense/voxel_cloud_t.hpp"

namespace shapesense {

// The rig and one background per camera, in rig order.
struct RigSetup {
  Rig rig;
  std::vector<cv::Mat> backgrounds;
};

// Reads the rig file (OpenCV YAML, docs/dataset.md) and
// `background_folder`/<camera>.png for each camera; with an empty folder, no
// backgrounds. InputError naming the file on anything missing or malformed.
RigSetup LoadRigSetup(const std::filesystem::path& rig_file,
                      const std::filesystem::path& background_folder);

std::vector<std::string> CameraNames(const Rig& rig);

// Decodes an image of `camera` to 8-bit BGR of the camera's size (a raw BGR8
// image becomes a view of the message's bytes). "" or the reason.
std::string DecodeImage(const image_t& image, const Camera& camera, cv::Mat* bgr);
// The same with the image's bytes elsewhere (DecodeImageFields).
std::string DecodeImage(const image_t& image, std::span<const uint8_t> bytes, const Camera& camera,
                        cv::Mat* bgr);

// The stage times a frame-set brings: those of its images merged by name
// (a stage of the set lasted as long as its slowest image), plus
// "transport": the longest time from an image's publication to its arrival,
// ending when the set was complete.
std::vector<stage_time_t> FrameSetStageTimes(const FrameSet& set);

// One image reduced to what carving needs of it: its silhouette, and the
// silhouette compacted for the shape stage. The carving service prepares
// each image as it arrives, while the rest of its frame-set is still on the
// way, so a set's carving waits for its last image's silhouette only.
struct PreparedView {
  Silhouette silhouette;
  CompactSilhouette compact;
  int64_t start_utime = 0;  // decoding began
  int64_t end_utime = 0;    // compaction ended; 0: not prepared (yet)
  // Why the image could not be prepared ("" when it was, or was not tried):
  // its set then fails to carve with this reason.
  std::string error;
};

// What CarvingStage produces; kept between frame-sets so buffers are reused.
struct CarvingOutput {
  voxel_cloud_t message;  // trigger, grid, voxels, stage times; the header is the publisher's
  // The silhouettes compacted for the shape stage, and as the message that
  // carries them (its header is the publisher's).
  SilhouetteSet compact;
  silhouettes_t silhouettes_message;
  std::vector<Silhouette> silhouettes;
  std::vector<PreparedView> views;  // Process's
  CompactScratch compact_scratch;   // Process's
  VoxelCloud cloud;
};

// Decode and silhouettes (PrepareView, per image), hierarchical carving
// (Carve). Stage times: "silhouette", from the first preparation the
// complete set still waited for to the last one's end, and "carving".
class CarvingStage {
 public:
  // Builds the carver's lookup table (about 1 s at 256³ voxels). Throws
  // InputError on backgrounds that do not fit the rig, std::invalid_argument
  // on options that fail validation.
  CarvingStage(const Rig& rig, std::vector<cv::Mat> backgrounds,
               const SilhouetteOptions& silhouette, const CarvingOptions& carving,
               const ProgressCallback& table_progress = {});

  // Decodes `image`, the image of the rig's camera `camera`, then extracts
  // and compacts its silhouette. "" or why the image cannot be used (it does
  // not decode, or does not fit the camera). Thread-safe: the scratch is the
  // caller's.
  std::string PrepareView(size_t camera, const image_t& image, PreparedView* view,
                          CompactScratch* scratch) const;
  // The same with the image's bytes elsewhere (DecodeImageFields): the
  // carving service prepares each image inside its LCM callback, from the
  // received buffer itself. `view->error` keeps the reason too.
  std::string PrepareView(size_t camera, const image_t& image, std::span<const uint8_t> bytes,
                          PreparedView* view, CompactScratch* scratch) const;

  // Carves `set` from its images' views: (*views)[k] prepared from
  // set.images[k], or empty (`end_utime` 0) to be prepared here when that
  // image still holds its bytes (else the set fails: its view was lost). The views
  // are swapped into `out`, and come back holding its earlier buffers. ""
  // on success, else why the set could not be carved; `out->message` is then
  // stale.
  std::string Carve(const FrameSet& set, std::vector<PreparedView>* views,
                    CarvingOutput* out) const;

  // Carve with every view prepared here (replay, tests).
  std::string Process(const FrameSet& set, CarvingOutput* out) const;

  const Rig& rig() const { return rig_; }

 private:
  Rig rig_;
  SilhouetteStage silhouettes_;
  Carver carver_;
};

// What the shape stage needs to sense the configuration q of the shape
// (libs/mechanics/configuration_sensing.h).
struct ConfigurationSetup {
  ManipulatorGeometry geometry;  // rest lengths of the model file, base pose, tapes
  ConfigurationSensingOptions options;
};

struct ShapeOutput {
  shape_t message;  // trigger and stage times from the cloud, + "shape"; header the publisher's
  ShapeEstimate estimate;  // as measured (shape_t has no tube radius)
  // When the stage senses q: q (message.has_configuration, q,
  // configuration_residual_mm) or why not (reason); else invalid, no reason.
  ConfigurationMeasurement configuration;
  // Set when the shape was measured without the silhouettes it should have
  // had (they were missing or malformed): the reason.
  std::string warning;
  // Expanded from the set's compact ones; the buffers are kept between
  // calls, since an expansion into an earlier one clears only what that wrote.
  std::vector<Silhouette> silhouettes;
  bool refined = false;  // the estimate used `silhouettes`
  size_t tape_runs = 0;  // runs of tape in them, all cameras
  VoxelCloud cloud;
};

// Voxel cloud → shape, refined against the compact silhouettes the carving
// stage made of the same frame-set, and with a `configuration` setup the
// configuration q of the shape ("shape": expansion, estimation and q).
class ShapeStage {
 public:
  // Throws std::invalid_argument on options or a geometry that fail validation.
  ShapeStage(const Rig& rig, const ShapeOptions& shape,
             std::optional<ConfigurationSetup> configuration = {});

  // Whether Process wants the silhouettes (refinement is on).
  bool wants_silhouettes() const { return wants_silhouettes_; }
  // Whether Process senses q.
  bool senses_configuration() const { return configuration_.has_value(); }

  const Rig& rig() const { return rig_; }

  // `silhouettes`: those of the cloud's frame-set (SilhouettesFromMessage),
  // or nullptr. "" when a shape was produced (valid or not: an estimate that
  // fails carries its error in the message); else why the cloud itself is
  // malformed, and nothing to publish.
  std::string Process(const voxel_cloud_t& voxels, const SilhouetteSet* silhouettes,
                      ShapeOutput* out) const;

 private:
  // Fills out->silhouettes from the set, when it is there, of the cloud's
  // frame-set and of the rig's cameras; "" or why they could not be had.
  std::string ExpandSilhouettes(const voxel_cloud_t& voxels, const SilhouetteSet* set,
                                ShapeOutput* out) const;
  // out->configuration from out->estimate.
  void SenseConfigurationOf(ShapeOutput* out) const;

  Rig rig_;
  bool wants_silhouettes_;
  ShapeEstimator estimator_;
  std::optional<ConfigurationSetup> configuration_;
};

}  // namespace shapesense
