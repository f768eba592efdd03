#pragma once

// The pipeline latency bench's cameras: a synthetic rig, its backgrounds, and
// frame-sets of the virtual rig's manipulator moving along its built-in
// trajectory (libs/sim/trajectory.h), rendered ahead of time and
// turned into image messages the way the capture service builds them; the
// bench only stamps the trigger and publishes.
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "libs/camera/camera.h"
#include "runtime/lcm/image_buses.h"
#include "runtime/lcm/lcm_bus.h"
#include "shapesense/image_t.hpp"

namespace shapesense::bench {

struct BenchRigOptions {
  int width = 640;
  int height = 480;
  int frame_sets = 24;  // distinct sets, spread over one loop of the trajectory
  int threads = 2;      // rendering
};

struct BenchRig {
  Rig rig;
  std::vector<cv::Mat> backgrounds;  // the backdrop alone, per camera
  // [set][camera]: BGR8 messages as the capture service publishes them.
  std::vector<std::vector<image_t>> frame_sets;
};

// Renders everything (about 20 ms per 640×480 view and core). Throws
// std::invalid_argument on a size the synthetic rig refuses.
BenchRig MakeBenchRig(const BenchRigOptions& options);

// Writes `folder`/rig.yaml and `folder`/background/<camera>.png.
void WriteBenchRig(const BenchRig& bench_rig, const std::filesystem::path& folder);

// Publishes the prepared frame-sets as a capture service with instant
// cameras would: every image of a set carries the trigger sequence and the
// trigger time, taken when publishing starts, so the time from trigger to
// shape is what the pipeline adds.
class FrameSetPlayer {
 public:
  // `bench_rig` must outlive the player (its messages are stamped in place).
  FrameSetPlayer(BenchRig& bench_rig, const std::string& lcm_url);

  // Publishes set `trigger_seq` (the prepared sets in turn); returns the
  // trigger time, or -1 when LCM refused an image.
  int64_t Publish(int64_t trigger_seq);
  int64_t cameras() const { return static_cast<int64_t>(channels_.size()); }

 private:
  BenchRig& rig_;
  LcmBus bus_;              // publishing only: no subscription, so no receive socket
  ImageBuses image_buses_;  // each camera on its port, as the capture service publishes
  std::vector<std::string> channels_;
  std::vector<int64_t> camera_seq_;
};

}  // namespace shapesense::bench
