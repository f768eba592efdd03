#pragma once

// shapesense-shape: voxel cloud + compact silhouettes → shape, over LCM.
//
// The shape is refined against the silhouettes' sub-pixel edges. The carving
// service sends them compacted (silhouettes_t: the mask and tape as runs, the
// difference image only along the outline; tens of kB, one datagram), so
// this service receives no image: it needs no backgrounds, extracts nothing
// again, and can run on another host than the cameras. It pairs each voxel
// cloud with its silhouettes by trigger sequence and time.
#include <array>
#include <atomic>
#include <deque>
#include <optional>
#include <ostream>
#include <string>

#include "libs/centerline/shape_estimator.h"
#include "libs/mechanics/base_pose.h"
#include "libs/mechanics/configuration_sensing.h"
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
  // world_from_base, the base frame in the cameras' world (the keys
  // base_position and base_rotation, as the virtual rig's plant has them).
  BasePose base;
  TapeLayout tapes;
  ConfigurationSensingOptions sensing;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("enabled", enabled, "sense q (else has_configuration is false)");
    visit("manipulator", manipulator,
          "manipulator model file (rest lengths), relative to this file; needed when enabled");
    base.VisitFields(visit);
    visit("tapes", tapes, "tape bands: at the junction, before the tip, optionally proximal");
    visit("sensing", sensing, "measuring the sections and fitting the arc");
  }
  std::string Validate() const;
};

// config/shape_service.yaml documents every key.
struct ShapeServiceOptions {
  // Rig file, relative to the config file's folder.
  std::string rig;
  ShapeOptions shape;
  // How long a voxel cloud waits for its silhouettes before it is measured
  // without refinement, and silhouettes for their voxel cloud, ms.
  double pairing_timeout_ms = 500.0;
  // Voxel clouds, and silhouettes, waiting for their partner at once; past
  // it the oldest cloud is measured unrefined, the oldest silhouettes forgotten.
  int max_waiting = 8;
  // Voxel clouds waiting for the worker; on overload the oldest is dropped.
  int queue_capacity = 2;
  std::string lcm_url;
  ShapeConfigurationOptions configuration;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("rig", rig, "rig file (OpenCV YAML), relative to this file");
    visit("shape", shape, "centreline and markers");
    visit("pairing_timeout_ms", pairing_timeout_ms,
          "wait of a voxel cloud for its silhouettes and of silhouettes for their cloud, ms "
          "(1-60000)");
    visit("max_waiting", max_waiting,
          "voxel clouds, and silhouettes, waiting for their partner at once (1-1000)");
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
  // Subscribes to the voxels (and, when refining, the silhouettes) and
  // starts the worker. `configuration`: LoadConfigurationSetup(options).
  // Throws std::invalid_argument when `configuration` and
  // options.configuration.enabled disagree.
  ShapeService(const ShapeServiceOptions& options, const Rig& rig, LcmBus& bus,
               std::optional<ConfigurationSetup> configuration = {});
  ShapeService(const ShapeService&) = delete;
  ShapeService& operator=(const ShapeService&) = delete;

  // Measures voxel clouds whose silhouettes did not come in time, forgets
  // old silhouettes, publishes the status when due. Call from the bus's thread.
  void Poll(int64_t now_utime);
  service_status_t Status(int64_t now_utime);
  // Whether the worker has been on one job for longer than `limit` (hung).
  bool WorkerBusyLongerThan(std::chrono::microseconds limit) const {
    return worker_.BusyLongerThan(limit);
  }

 private:
  struct Job {
    voxel_cloud_t voxels;
    std::optional<SilhouetteSet> silhouettes;
    // The measurement's instant on this host's clock (the cloud's receive
    // time less its age at publish): what dates the shape, hop by hop.
    int64_t measured_utime = 0;
  };
  template <class Message>
  struct Waiting {
    Message message;
    int64_t receive_utime = 0;   // for the pairing timeout
    int64_t measured_utime = 0;  // a cloud's: as Job's
  };

  // The cloud is moved in from the LCM callback (tens of kB every frame-set);
  // the silhouettes are unpacked into a SilhouetteSet.
  void OnSilhouettes(const silhouettes_t& message, int64_t receive_utime);
  void OnVoxels(voxel_cloud_t&& voxels, int64_t receive_utime);
  void MeasureAndPublish(const Job& job);
  void PushUnrefined(Waiting<voxel_cloud_t>& waiting);

  ShapeServiceOptions options_;
  LcmBus& bus_;
  ShapeStage stage_;
  int64_t pairing_timeout_us_;
  // The bus thread's: the pairing.
  std::deque<Waiting<SilhouetteSet>> waiting_silhouettes_;
  std::deque<Waiting<voxel_cloud_t>> waiting_voxels_;
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
