#pragma once

// Every camera of a rig served as a real GigE Vision camera through Aravis's
// ArvGvFakeCamera, each on its own address (127.0.0.1, 127.0.0.2 ... inside a
// network namespace: the address must belong to an interface).
//
// Each camera times its images as a PTP-synchronised industrial camera
// does: a software trigger starts an exposure when it reaches the camera (a
// watcher thread, at real-time priority where allowed, sees each camera's
// trigger register flip within a quarter of a millisecond); the image shows the scene at that
// instant (the trajectory, or in plant mode the plant: plant_world.h) and is stamped with it on the
// host's clock, which is the virtual rig's PTP time; its block id counts
// the camera's exposures. A trigger that arrives while the camera still
// waits to serve the last one is missed, as on a real camera that is busy:
// no exposure, no frame id. No camera knows of frame-sets: the capture
// service proves which trigger each image answers from these facts alone.
// Each camera renders its own view (its own SceneRenderer) on the render
// threads, in the pixel format the client set.
//
// Faults for tests (SetFaults): images answered late, by a random delay
// after their exposure (the camera misses the triggers that come meanwhile),
// triggers missed at random, and triggers answered with the previous image
// again (a stale buffer re-sent: same frame id, stamp and pixels).

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/sim/trajectory.h"
#include "libs/sim/tube_scene.h"
#include "services/rig_sim/plant_world.h"

namespace shapesense {

// One exposure of one camera: when, and the scene it saw.
struct CameraExposure {
  int camera = 0;
  int64_t frame_id = 0;    // the camera's exposures, from 1 (GigE Vision block id: 1-65535)
  int64_t utime = 0;       // exposure start, µs since epoch (host clock = the rig's PTP time)
  double t_seconds = 0.0;  // trajectory time of its scene
  TrajectoryPose pose;     // the trajectory's (not set in plant mode)
  std::shared_ptr<const TubeScene> scene;
};

struct CameraFaults {
  double answer_delay_max_ms = 0.0;  // each image sent 0 to this long after its exposure
  double miss_ratio = 0.0;           // fraction of triggers the cameras miss
  // Fraction of triggers a camera answers with its previous image again (the
  // same frame id, exposure stamp and pixels), as a camera re-sending a
  // stale buffer: one image answering two triggers.
  double repeat_ratio = 0.0;
  uint32_t seed = 1;
};

class FakeCameraServer {
 public:
  // `addresses`: one per rig camera. `origin_utime` is trajectory time 0.
  // `seed` seeds the pixel noise. Starts no camera.
  FakeCameraServer(Rig rig, TrajectoryOptions trajectory, std::vector<std::string> addresses,
                   uint32_t seed, int64_t origin_utime);
  ~FakeCameraServer();
  FakeCameraServer(const FakeCameraServer&) = delete;
  FakeCameraServer& operator=(const FakeCameraServer&) = delete;

  // Serves camera `camera` (rig order) as device "Aravis-Fake-<serial>"
  // (serial: the camera's name, or SIM<i> when longer than 15 characters).
  // Throws std::runtime_error naming camera and address when it cannot bind.
  void Start(int camera);
  // Takes the camera off the network (its clients lose it); Start() again
  // brings it back.
  void Stop(int camera);
  bool Running(int camera) const;
  int num_cameras() const { return static_cast<int>(slots_.size()); }
  const std::string& serial(int camera) const;

  // The fraction of stream packets every camera drops (now and after restarts).
  void SetPacketLoss(double ratio);
  // Show the backdrop alone (no manipulator); frame-sets are still counted.
  void SetBackdropOnly(bool backdrop_only) { backdrop_only_ = backdrop_only; }
  // Plant mode: every frame-set shows the plant at its trigger time instead
  // of the trajectory (its scene carries the plant's q). Before any Start().
  void SetPlant(std::shared_ptr<PlantWorld> plant) { plant_ = std::move(plant); }

  // Faults from now on (none by default).
  void SetFaults(const CameraFaults& faults);

  // The reference camera's (camera 0's) exposures since the last call,
  // oldest first (at most 1000 kept): the rig's truth is published for each.
  std::vector<CameraExposure> TakeReferenceExposures();
  // One of a camera's last 1000 exposures, by frame id.
  std::optional<CameraExposure> FindExposure(int camera, int64_t frame_id) const;
  // What camera `camera` shows for its `exposure`: BGR at the rig camera's
  // size, by SceneRenderer::RenderImage (the backdrop's own rendering, with
  // its own noise, when backdrop only).
  cv::Mat Render(const CameraExposure& exposure) const;

  int64_t images_served() const { return images_served_; }
  int64_t errors() const { return errors_; }

  // The fill of one image (called by the camera's thread through Aravis):
  // the exposure it shows.
  struct Stamp {
    int64_t frame_id = 0;
    int64_t exposure_utime = 0;
  };
  Stamp Fill(int camera, void* data, int width, int height, uint32_t pixel_format);

  struct Slot;  // one camera's state (fake_camera_server.cc)

 private:
  CameraExposure Expose(int camera, int64_t utime);
  void WatchTriggers();
  void WatchTrigger(Slot& slot);
  // Render() on a render thread, waiting for it.
  cv::Mat RenderOnWorker(const CameraExposure& exposure);
  void RenderJobs();
  void DelayAnswer();
  bool RepeatsLastImage(const Slot& slot, size_t size);
  void KeepForRepeats(Slot& slot, const void* data, size_t size, const Stamp& stamp);

  const Rig rig_;
  const TrajectoryOptions trajectory_;
  const uint32_t seed_;
  const int64_t origin_utime_;
  std::shared_ptr<PlantWorld> plant_;  // plant mode; null: the trajectory
  std::vector<std::unique_ptr<Slot>> slots_;
  std::atomic<double> packet_loss_{0.0};
  std::atomic<bool> backdrop_only_{false};
  // Start() and Stop() against the watcher of triggers.
  mutable std::mutex slots_mutex_;
  std::atomic<bool> stop_watching_{false};
  std::thread watcher_;

  mutable std::mutex mutex_;  // the exposures, the faults' random numbers and the plant
  std::deque<CameraExposure> new_reference_;
  std::vector<std::deque<CameraExposure>> history_;  // per camera
  CameraFaults faults_;
  std::mt19937 fault_random_{1};
  std::atomic<int64_t> images_served_{0};
  std::atomic<int64_t> errors_{0};

  std::mutex render_mutex_;
  std::condition_variable render_ready_;
  std::deque<std::packaged_task<cv::Mat()>> render_jobs_;
  bool stop_rendering_ = false;
  std::vector<std::thread> render_threads_;  // last: they use the above
};

}  // namespace shapesense
