#pragma once

// shapesense-shape: voxel cloud (+ the frame-set's images) → shape, over LCM.
//
// The shape is refined against the silhouettes' sub-pixel edges, so this
// service needs the images too. It subscribes to the cameras as the carving
// service does, assembles the same frame-sets (FrameSetAssembler) and
// extracts their silhouettes again (about 0.1 ms per 640×480 image), then
// pairs each voxel cloud with its frame-set by trigger sequence and time.
// The alternative, the carving service sending edge data, would save that
// work but tie the two services to one more message format; the images are
// multicast to every subscriber anyway, so the network carries them once.
#include <array>
#include <atomic>
#include <deque>
#include <optional>
#include <ostream>
#include <string>

#include "libs/centerline/shape_estimator.h"
#include "libs/mechanics/configuration_sensing.h"
#include "libs/silhouette/silhouette.h"
#include "runtime/lcm/frame_set_assembler.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/lcm/pipeline_stages.h"
#include "runtime/lcm/service_main.h"
#include "runtime/lcm/service_status.h"
#include "runtime/lcm/service_worker.h"

namespace shapesense {

// The `configuration:` section: the configuration q = [kappa_x, kappa_z,
// eps0, eps1] of every shape, in shape_t (has_configuration, q,
// configuration_residual_mm); see libs/mechanics/configuration_sensing.h and
// docs/mechanics.md for the tape layout and how q is measured.
struct ShapeConfigurationOptions {
  bool enabled = false;
  // The manipulator model file (its rest lengths L0, L1; config/manipulator.yaml),
  // relative to the config file's folder.
  std::string manipulator;
  // world_from_base, the base frame in the cameras' world: x_world =
  // R x_base + base_position (mm), R the rotation by the rotation vector
  // base_rotation (unit axis times angle, rad). The base frame's y axis runs
  // along the manipulator: [1.5707963267948966, 0, 0] turns it onto world +z.
  std::array<double, 3> base_position = {0.0, 0.0, 0.0};
  std::array<double, 3> base_rotation = {0.0, 0.0, 0.0};
  TapeLayout tapes;
  ConfigurationSensingOptions sensing;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("enabled", enabled, "sense q (else has_configuration is false)");
    visit("manipulator", manipulator,
          "manipulator model file (rest lengths), relative to this file; needed when enabled");
    visit("base_position", base_position, "world_from_base: the base's origin in the world, mm");
    visit("base_rotation", base_rotation,
          "world_from_base: rotation vector (axis * angle, rad); [1.5707963267948966, 0, 0] "
          "turns the base's y axis (along the manipulator) onto world +z");
    visit("tapes", tapes, "tape bands: at the junction, before the tip, optionally proximal");
    visit("sensing", sensing, "measuring the sections and fitting the arc");
  }
  std::string Validate() const;
  Pose3 WorldFromBase() const;
};

// config/shape_service.yaml documents every key.
struct ShapeServiceOptions {
  // Rig file and the folder of backgrounds (<camera>.png); relative paths are
  // relative to the config file's folder. Backgrounds are needed only for
  // the refinement against the silhouettes (shape.refine_with_silhouettes).
  std::string rig;
  std::string backgrounds;
  // For the refinement; keep it equal to the carving service's.
  SilhouetteOptions silhouette;
  ShapeOptions shape;
  FrameSetAssemblyOptions assembly;
  // How long a voxel cloud waits for its frame-set before it is measured
  // without refinement, and a frame-set for its voxel cloud, ms.
  double pairing_timeout_ms = 500.0;
  // Voxel clouds waiting for the worker; on overload the oldest is dropped.
  int queue_capacity = 2;
  std::string lcm_url;
  ShapeConfigurationOptions configuration;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("rig", rig, "rig file (OpenCV YAML), relative to this file");
    visit("backgrounds", backgrounds,
          "folder of <camera>.png backgrounds, relative to this file (for the refinement)");
    visit("silhouette", silhouette,
          "silhouette extraction for the refinement (as the carving service's)");
    visit("shape", shape, "centreline and markers");
    visit("assembly", assembly, "frame-set assembly");
    visit("pairing_timeout_ms", pairing_timeout_ms,
          "wait of a voxel cloud for its images and of images for their cloud, ms (1-60000)");
    visit("queue_capacity", queue_capacity, "voxel clouds waiting for the worker (1-100)");
    visit("lcm_url", lcm_url, "LCM provider URL (empty: LCM_DEFAULT_URL or LCM's default)");
    visit("configuration", configuration,
          "the configuration q of each shape (tape markers + arc fit; off by default)");
  }
  std::string Validate() const;
};

// The shape stage's configuration setup of the options: nullopt when
// configuration.enabled is off, else the model file's rest lengths with the
// section's base pose, tapes and sensing options. Throws InputError naming
// the file on a model file that cannot be read or parsed, or naming the key
// when the tapes do not fit the model's sections.
std::optional<ConfigurationSetup> LoadConfigurationSetup(const ShapeServiceOptions& options);

// The service on a bus that someone else handles (RunShapeService, or a test
// running several services on one memq:// bus).
// LcmBus cannot unsubscribe: the bus must outlive the service and must not
// be handled once the service is gone.
class ShapeService {
 public:
  // Subscribes to the voxels (and, when refining, the cameras) and starts
  // the worker. `configuration`: LoadConfigurationSetup(options). Throws
  // InputError on backgrounds that do not fit the rig,
  // std::invalid_argument when `configuration` and
  // options.configuration.enabled disagree.
  ShapeService(const ShapeServiceOptions& options, RigSetup setup, LcmBus& bus,
               std::optional<ConfigurationSetup> configuration = {});
  ShapeService(const ShapeService&) = delete;
  ShapeService& operator=(const ShapeService&) = delete;

  // Measures voxel clouds whose images did not come in time, forgets old
  // frame-sets, publishes the status when due. Call from the bus's thread.
  void Poll(int64_t now_utime);
  service_status_t Status(int64_t now_utime);

 private:
  struct Job {
    voxel_cloud_t voxels;
    std::optional<FrameSet> images;
  };
  struct WaitingVoxels {
    voxel_cloud_t voxels;
    int64_t receive_utime = 0;
  };
  struct WaitingImages {
    FrameSet set;
    int64_t complete_utime = 0;
  };

  void OnImage(image_t&& image, int64_t receive_utime);
  // Moved in from the LCM callback: a cloud is tens of kB, every frame-set.
  void OnVoxels(voxel_cloud_t&& voxels, int64_t receive_utime);
  void OnFrameSet(FrameSet set);
  void CountAssemblyDrops(int64_t before);
  void MeasureAndPublish(const Job& job);

  ShapeServiceOptions options_;
  LcmBus& bus_;
  ShapeStage stage_;
  int64_t pairing_timeout_us_;
  // The bus thread's: assembly and pairing.
  FrameSetAssembler assembler_;
  std::deque<WaitingImages> waiting_images_;
  std::deque<WaitingVoxels> waiting_voxels_;
  ServiceStatus status_{"shape"};
  ShapeOutput output_;  // the worker's, reused
  int64_t shape_seq_ = 0;
  ServiceWorker<Job> worker_;  // last: see ServiceWorker
};

ShapeServiceOptions LoadShapeServiceOptions(const ServiceArgs& args);

// Loads and checks everything before opening LCM, then runs until `stop` or
// the duration. Returns the last status. Throws InputError on bad input,
// std::runtime_error when LCM cannot start.
service_status_t RunShapeService(const ServiceArgs& args, const std::atomic<bool>& stop,
                                 std::ostream& log);

}  // namespace shapesense
