#pragma once

// Every camera of a rig served as a real GigE Vision camera through Aravis's
// ArvGvFakeCamera, each on its own address (127.0.0.1, 127.0.0.2 ... inside a
// network namespace: the address must belong to an interface). A camera's
// image is made when it is triggered: the frame-set it belongs to is chosen
// by a FrameSetClock from the time its trigger arrived (a watcher thread
// sees each camera's trigger register flip), the set's scene is the
// trajectory (or, in plant mode, the plant: plant_world.h) at the time the
// set's first trigger arrived, and each camera
// renders its own view of it (in its own thread, with its own SceneRenderer)
// in the pixel format the client set. The image's timestamp is its
// trigger's arrival, its exposure, whenever the camera's thread got to it.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/sim/tube_scene.h"
#include "services/rig_sim/frame_set_clock.h"
#include "services/rig_sim/plant_world.h"
#include "services/rig_sim/trajectory.h"

namespace shapesense {

struct FrameSet {
  int64_t seq = 0;
  int64_t trigger_utime = 0;  // the set's first trigger, µs since epoch
  double t_seconds = 0.0;     // trajectory time of its scene
  TrajectoryPose pose;        // the trajectory's (not set in plant mode)
  std::shared_ptr<const TubeScene> scene;
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

  // Frame-sets opened since the last call, oldest first (at most 1000 kept).
  std::vector<FrameSet> TakeNewFrameSets();
  // One of the last 1000 frame-sets.
  std::optional<FrameSet> Find(int64_t seq) const;
  // What camera `camera` shows for `set`: BGR at the rig camera's size (the
  // backdrop's own rendering, with its own noise, when backdrop only).
  cv::Mat Render(int camera, const FrameSet& set) const;

  int64_t images_served() const { return images_served_; }
  int64_t errors() const { return errors_; }

  // The fill of one image (called by the camera's thread through Aravis).
  // Returns how long its trigger waited for the camera's thread, µs.
  int64_t Fill(int camera, void* data, int width, int height, uint32_t pixel_format);

  struct Slot;  // one camera's state (fake_camera_server.cc)

 private:
  FrameSet Assign(int camera, int64_t trigger_utime);
  void WatchTriggers();
  // Render() on a render thread, waiting for it.
  cv::Mat RenderOnWorker(int camera, const FrameSet& set);
  void RenderJobs();

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

  mutable std::mutex mutex_;  // the clock and the frame-set lists
  FrameSetClock clock_;
  std::deque<FrameSet> new_sets_;
  std::deque<FrameSet> history_;
  std::atomic<int64_t> images_served_{0};
  std::atomic<int64_t> errors_{0};

  std::mutex render_mutex_;
  std::condition_variable render_ready_;
  std::deque<std::packaged_task<cv::Mat()>> render_jobs_;
  bool stop_rendering_ = false;
  std::vector<std::thread> render_threads_;  // last: they use the above
};

}  // namespace shapesense
