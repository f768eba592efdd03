#pragma once

// shapesense-carving: camera images → silhouettes → frame-sets → voxel
// cloud, over LCM. The LCM callback checks each image, extracts its
// silhouette while the rest of its frame-set is still on the way, and
// assembles (it never blocks or throws); a bounded queue hands complete
// frame-sets with their silhouettes to one worker, which carves; on
// overload the oldest set is dropped.
#include <atomic>
#include <functional>
#include <optional>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "libs/carving/carver.h"
#include "libs/silhouette/silhouette.h"
#include "runtime/lcm/frame_set_assembler.h"
#include "runtime/lcm/image_buses.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/lcm/pipeline_stages.h"
#include "runtime/lcm/service_main.h"
#include "runtime/lcm/service_status.h"
#include "runtime/lcm/service_worker.h"
#include "services/carving/prepared_views.h"

namespace shapesense {

// config/carving_service.yaml documents every key.
struct CarvingServiceOptions {
  // Rig file and the folder of backgrounds (<camera>.png); relative paths are
  // relative to the config file's folder.
  std::string rig;
  std::string backgrounds;
  SilhouetteOptions silhouette;
  CarvingOptions carving;
  FrameSetAssemblyOptions assembly;
  // Complete frame-sets waiting for the worker; on overload the oldest is dropped.
  int queue_capacity = 2;
  // Silhouettes published for monitoring, per second (0: none).
  double silhouette_rate_hz = 1.0;
  // LCM provider URL; empty: LCM_DEFAULT_URL or LCM's default.
  std::string lcm_url;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("rig", rig, "rig file (OpenCV YAML), relative to this file");
    visit("backgrounds", backgrounds, "folder of <camera>.png backgrounds, relative to this file");
    visit("silhouette", silhouette, "silhouette extraction");
    visit("carving", carving, "voxel carving");
    visit("assembly", assembly, "frame-set assembly");
    visit("queue_capacity", queue_capacity, "frame-sets waiting for the worker (1-100)");
    visit("silhouette_rate_hz", silhouette_rate_hz,
          "monitoring silhouettes per second (0-100, 0: off)");
    visit("lcm_url", lcm_url, "LCM provider URL (empty: LCM_DEFAULT_URL or LCM's default)");
  }
  std::string Validate() const;
};

// A complete frame-set and the views prepared of its images on arrival.
struct CarvingJob {
  FrameSet set;
  std::vector<PreparedView> views;
};

// Seams for tests; empty in the service.
struct CarvingServiceHooks {
  // Called by the worker before it carves a frame-set (a test can hold the
  // worker here to overload the queue).
  std::function<void(const FrameSet&)> before_carving;
};

// The service on a bus that someone else handles (RunCarvingService, or a
// test running several services on one memq:// bus).
// LcmBus cannot unsubscribe: the bus must outlive the service and must not
// be handled once the service is gone.
class CarvingService {
 public:
  // Builds the carving table (about 1 s at 256³ voxels), subscribes to the
  // camera channels and starts the worker. `options` validated, `setup` with
  // backgrounds. Throws InputError on backgrounds that do not fit the rig.
  CarvingService(const CarvingServiceOptions& options, RigSetup setup, LcmBus& bus,
                 CarvingServiceHooks hooks = {});
  CarvingService(const CarvingService&) = delete;
  CarvingService& operator=(const CarvingService&) = delete;

  // Drops frame-sets that timed out and publishes the status when due. Call
  // from the thread that handles the bus.
  void Poll(int64_t now_utime);

  // The status as it would be published now.
  service_status_t Status(int64_t now_utime);
  // Whether the worker has been on one job for longer than `limit` (hung).
  bool WorkerBusyLongerThan(std::chrono::microseconds limit) const {
    return worker_.BusyLongerThan(limit);
  }
  // The buses to handle: the one given and the cameras' image buses
  // (runtime/lcm/image_buses.h), all on the same thread.
  std::vector<LcmBus*> Buses() const;
  const AssemblyCounters& assembly() const { return assembler_.counters(); }

 private:
  void SubscribeToImages(const std::vector<std::string>& cameras);
  // An image as received, read in place: its fields are decoded, its bytes
  // only read into its silhouette (never copied). "" or why the buffer is
  // no image_t. `camera`: the camera whose bus it came on, or "" on the
  // shared bus.
  std::string OnImageBytes(std::span<const uint8_t> buffer, const std::string& channel,
                           const std::string& camera, int64_t receive_utime);
  // `image`: its fields, its bytes in `bytes`.
  void OnImage(image_t&& image, std::span<const uint8_t> bytes, const std::string& channel,
               const std::string& camera, int64_t receive_utime);
  // Whether an image may join the assembly: valid, on its camera's bus and
  // channel. Counts and notes a refusal.
  bool AcceptableImage(const image_t& image, std::span<const uint8_t> bytes,
                       const std::string& channel, const std::string& camera);
  // The camera's index in the rig, or -1.
  int RigIndex(const std::string& camera) const;
  struct ArrivedView {
    ImageIdentity image;
    PreparedView view;
  };
  // The view of an image about to be assembled, or nullopt when its camera
  // is not the rig's. One that does not decode keeps the reason, which its
  // set, if it completes, reports as its error.
  std::optional<ArrivedView> PrepareOnArrival(const image_t& image, std::span<const uint8_t> bytes);
  void CountAssemblyDrops(int64_t before);
  void CarveAndPublish(CarvingJob& job);
  void MaybePublishSilhouettes(const FrameSet& set);

  CarvingServiceOptions options_;
  LcmBus& bus_;
  ImageBuses image_buses_;
  CarvingServiceHooks hooks_;
  CarvingStage stage_;
  FrameSetAssembler assembler_;     // the bus thread's
  PreparedViews prepared_;          // the bus thread's
  CompactScratch compact_scratch_;  // the bus thread's
  ViewPool view_pool_;              // shared by the bus thread and the worker
  ServiceStatus status_{"carving"};
  CarvingOutput output_;  // the worker's, reused
  int64_t voxels_seq_ = 0;
  int64_t silhouette_seq_ = 0;
  int64_t last_silhouette_utime_ = 0;
  ServiceWorker<CarvingJob> worker_;  // last: see ServiceWorker
};

// The config with the command line's overrides, paths resolved, validated.
// Throws InputError naming the file and key.
CarvingServiceOptions LoadCarvingServiceOptions(const ServiceArgs& args);

// Loads and checks everything (config, rig, backgrounds) before opening LCM,
// then runs until `stop` or the duration. Returns the last status. Throws
// InputError on bad input, std::runtime_error when LCM cannot start.
service_status_t RunCarvingService(const ServiceArgs& args, const std::atomic<bool>& stop,
                                   std::ostream& log);

}  // namespace shapesense
