#pragma once

// What the simulated cameras of one capture process look at: a rig and the
// virtual rig's manipulator moving along its scripted trajectory
// (libs/sim/trajectory.h), rendered by libs/sim.

#include <cstdint>
#include <string>

#include "libs/camera/camera.h"
#include "libs/sim/trajectory.h"
#include "libs/sim/tube_scene.h"

namespace shapesense {

struct SimulationOptions {
  // The motion, the tube and how it is rendered: as shapesense-rig-sim has them,
  // from `trajectory_file` (the rig-sim's config, e.g. config/rig_sim.yaml)
  // when given, else from `trajectory`.
  std::string trajectory_file;
  TrajectoryOptions trajectory;
  uint32_t seed = 0;  // pixel noise
  // False renders the backdrop alone (an empty scene, for backgrounds).
  bool show_manipulator = true;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("trajectory_file", trajectory_file,
          "rig-sim trajectory file (config/rig_sim.yaml); empty: `trajectory` below");
    visit("trajectory", trajectory,
          "the manipulator's motion and rendering (rig-sim TrajectoryOptions)");
    visit("seed", seed, "seed of the pixel noise");
    visit("show_manipulator", show_manipulator, "false: the backdrop alone (for backgrounds)");
  }
  std::string Validate() const;
};

// The shared, immutable description of a simulation: rig, trajectory, the
// time origin of the trajectory (t = 0 at `origin_utime`). Safe to share
// between threads.
class SimulatedWorld {
 public:
  // Throws std::invalid_argument on options that fail Validate() or an invalid rig.
  SimulatedWorld(Rig rig, SimulationOptions options, int64_t origin_utime);

  const Rig& rig() const { return rig_; }
  const SimulationOptions& options() const { return options_; }
  const RenderOptions& render() const { return options_.trajectory.render; }
  double SecondsAt(int64_t utime) const {
    return static_cast<double>(utime - origin_utime_) * 1e-6;
  }
  TrajectoryPose PoseAtUtime(int64_t utime) const {
    return PoseAt(options_.trajectory, SecondsAt(utime));
  }
  TubeScene SceneAtUtime(int64_t utime) const {
    return SceneOf(options_.trajectory, rig_, PoseAtUtime(utime));
  }

  // The noise seed of one camera's view of frame `frame` (the trigger
  // sequence, or the camera's own frame counter in free run): distinct for
  // every camera and frame, the same for the same inputs.
  uint32_t ViewSeed(int64_t frame, size_t camera_index) const;

 private:
  Rig rig_;
  SimulationOptions options_;
  int64_t origin_utime_;
};

}  // namespace shapesense
