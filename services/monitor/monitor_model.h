#pragma once

// What the web monitor shows, made from the rig's messages: each message
// becomes the JSON (or, for a camera, JPEG plus JSON) of one web channel
// (docs/monitor.md lists them). Camera pictures are joined to the
// silhouettes and the shape of their own frame-set by trigger sequence, so
// an overlay always belongs to the picture under it, whatever order the
// messages arrive in. No I/O: the monitor service feeds it from its bus
// thread and publishes what it returns.
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/geometry/types.h"
#include "libs/mechanics/configuration.h"
#include "runtime/rig/rig_status.h"
#include "shapesense/configuration_target_t.hpp"
#include "shapesense/estop_t.hpp"
#include "shapesense/image_t.hpp"
#include "shapesense/service_status_t.hpp"
#include "shapesense/shape_t.hpp"
#include "shapesense/silhouettes_t.hpp"
#include "shapesense/tendon_command_t.hpp"
#include "shapesense/tendon_state_t.hpp"
#include "shapesense/voxel_cloud_t.hpp"

namespace shapesense {

// One web channel's new message: JSON text, or a binary camera frame
// (little-endian u32 length, that many bytes of JSON, then the JPEG).
struct WebUpdate {
  std::string channel;  // "shape", "camera/cam0", "health", ...
  std::string payload;
  bool binary = false;
  // The same payload also goes to this Foxglove channel (kFoxglovePrefix +
  // channel; empty: none), stamped with `utime`.
  std::string foxglove_channel;
  int64_t utime = 0;
};

// The channels for Foxglove clients: the page's JSON of the same name under
// this prefix, and "fox/camera/<camera>", each picture as a
// foxglove.CompressedImage (JSON, its JPEG in base64).
inline constexpr const char* kFoxglovePrefix = "fox/";

struct MonitorModelOptions {
  std::string host;        // this monitor's host, for the page's title
  std::string rig_prefix;  // the rig's channel prefix, shown
  bool estop_enabled = false;
  int64_t started_utime = 0;
  // A camera picture waits this long (trigger time) for its frame-set's
  // shape; past it, it is shown without the shape.
  double overlay_wait_s = 0.5;
  // Frame-sets kept for pairing (shapes, silhouettes, waiting pictures).
  int kept_frame_sets = 64;
  // Programs whose status is older are stale, then missing, s (1 Hz statuses).
  double stale_after_s = 1.6;
  double missing_after_s = 2.5;
};

// Where a configuration target lies: the manipulator's rest lengths and
// its base in the cameras' world (the shape service's configuration section).
struct TargetGeometry {
  SectionLengths rest;
  Pose3 world_from_base = Pose3::Identity();
};

// The page's first message: the host, the cameras and their frusta.
std::string HelloJson(const MonitorModelOptions& options, const std::vector<Camera>& cameras);

class MonitorModel {
 public:
  // `cameras`: the rig's calibration (empty: pictures shown without the
  // projected shape); `rig`: the expected programs for the health table.
  // `geometry`: to draw a configuration target (none: only tip targets).
  MonitorModel(MonitorModelOptions options, std::vector<Camera> cameras, std::optional<RigFile> rig,
               std::optional<TargetGeometry> geometry);

  std::vector<WebUpdate> OnShape(const shape_t& shape, int64_t receive_utime);
  std::vector<WebUpdate> OnTruth(const shape_t& truth);
  std::vector<WebUpdate> OnSilhouettes(const silhouettes_t& silhouettes, int64_t receive_utime);
  // The visual hull, at most every kVoxelPeriodUs of trigger time: the
  // largest message, and a person sees no more.
  std::vector<WebUpdate> OnVoxels(const voxel_cloud_t& cloud);
  // A camera's preview (image_t, JPEG).
  std::vector<WebUpdate> OnPreview(image_t preview);
  std::vector<WebUpdate> OnStatus(const service_status_t& status, int64_t receive_utime);
  std::vector<WebUpdate> OnTarget(const configuration_target_t& target);
  std::vector<WebUpdate> OnTendonCommand(const tendon_command_t& command);
  std::vector<WebUpdate> OnTendonState(const tendon_state_t& state);
  std::vector<WebUpdate> OnEstop(const estop_t& estop);
  // The health table and the statistics (call a few times a second).
  std::vector<WebUpdate> Tick(int64_t now_utime);

 private:
  struct FrameSet {
    std::optional<shape_t> shape;
    std::optional<silhouettes_t> silhouettes;
    std::vector<image_t> previews;  // waiting for the shape
    int64_t trigger_utime = 0;
  };
  struct Stats {
    int64_t last_trigger_seq = -1;
    int64_t lost_sets = 0;
    int64_t invalid_shapes = 0;
    std::deque<int64_t> shape_receive_utimes;      // the last 2 s
    std::deque<int64_t> frame_set_receive_utimes;  // silhouettes: frame-sets carved
    std::deque<double> latencies_ms;               // trigger → received, the last 300
    std::map<std::string, double> stage_ms;        // the last shape's
  };

  FrameSet& FrameSetOf(int64_t trigger_seq, int64_t trigger_utime);
  void ForgetOldFrameSets();
  // Pictures of frame-sets whose shape will not come any more, or that came.
  std::vector<WebUpdate> ReleasePictures(int64_t newest_trigger_utime);
  WebUpdate CameraFrame(const image_t& preview, const FrameSet& set);
  void Count(const shape_t& shape, int64_t receive_utime);
  std::string ControllerJson() const;
  WebUpdate ControllerUpdate() const;
  std::vector<WebUpdate> ControllerIfDue(int64_t utime, bool changed);
  std::optional<Vec3> TargetTip() const;

  MonitorModelOptions options_;
  std::vector<Camera> cameras_;
  std::optional<TargetGeometry> geometry_;
  RigStatusBoard board_;
  std::map<int64_t, FrameSet> frame_sets_;  // by trigger sequence
  Stats stats_;
  std::optional<tendon_command_t> command_;
  std::optional<tendon_state_t> state_;
  std::optional<configuration_target_t> target_;
  std::optional<estop_t> estop_;
  std::optional<shape_t> last_shape_;
  int64_t controller_sent_utime_ = 0;
  int64_t voxels_sent_utime_ = 0;
};

}  // namespace shapesense
