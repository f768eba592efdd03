#pragma once

// shapesense-rig-sim: the virtual rig. A simulated manipulator follows a
// scripted trajectory (trajectory.h), rendered into every camera of a rig,
// each camera served as a real GigE Vision camera on its own address
// (fake_camera_server.h), so the capture service reads it with its Aravis
// backend over the real protocol. The ground truth at every exposure of the
// reference camera (the first) goes out on channels::kTruth (shape_t,
// runtime/lcm/truth_message.h); status at 1 Hz on channels::Status("rig_sim").
//
// Plant mode (--plant, plant_world.h): the manipulator is the tendon plant
// the controller drives over channels::kPlantCommand, its actuators
// published on channels::kPlantState; the truth carries the plant's q.
//
// Faults for tests: a ratio of lost stream packets (--packet-loss), images
// answered late (--answer-delay-ms), triggers missed (--miss-ratio) or
// answered with the previous image again (--repeat-ratio), and a
// camera taken off the network and brought back, on a schedule (--outage) or
// on request (SIGUSR1 stops the fault camera, SIGUSR2 starts it again).

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "libs/camera/camera.h"
#include "services/rig_sim/fake_camera_server.h"

namespace shapesense {

struct RigSimArgs {
  std::string rig_path;         // rig YAML; empty: MakeSyntheticRig with `seed`
  uint32_t seed = 0;            // synthetic rig jitter and pixel noise
  std::string trajectory_path;  // TrajectoryOptions YAML; empty: the defaults
  // PlantWorldOptions YAML (config/rig_plant.yaml): plant mode; empty: the trajectory.
  std::string plant_path;
  // One address per camera, in rig order; empty: 127.0.0.1, 127.0.0.2, ...
  std::vector<std::string> ips;
  double packet_loss = 0.0;  // fraction of GigE stream packets dropped (0-1)
  std::string lcm_url;       // empty: LCM's default
  double duration_s = 0.0;   // 0: until stopped
  // Scheduled outages "CAMERA:START_S:DURATION_S" (camera by name or index),
  // seconds from the start, e.g. "cam1:5:2".
  std::vector<std::string> outages;
  // The camera SIGUSR1 / SIGUSR2 (RigSimControl) stop and start; empty: the last.
  std::string fault_camera;
  // Serve the backdrop alone, no manipulator and no truth (for the capture
  // service's background command).
  bool backdrop_only = false;
  // Late answers and missed triggers, for tests (fake_camera_server.h).
  CameraFaults faults;
  // Write the rig in use (e.g. the synthetic one) here, for the other services.
  std::string write_rig_path;
};

// Requests from outside the run loop; a signal handler may set them.
struct RigSimControl {
  std::atomic<bool> stop_fault_camera{false};
  std::atomic<bool> start_fault_camera{false};
};

struct Outage {
  int camera = 0;
  double start_s = 0.0;
  double duration_s = 0.0;
};

// Parses "CAMERA:START_S:DURATION_S" for a camera of `rig` (name or index).
// Throws InputError naming the spec and what is wrong.
Outage ParseOutage(const std::string& spec, const Rig& rig);

// Loads and checks everything (throws InputError before serving anything),
// serves the cameras, publishes truth and status until `stop` is set or the
// duration has passed, then takes the cameras down. Prints one line per
// camera and "rig-sim: ready" once every camera serves. Throws
// std::runtime_error when a camera cannot be served or LCM cannot start.
void RunRigSim(const RigSimArgs& args, const std::atomic<bool>& stop,
               RigSimControl* control = nullptr);

}  // namespace shapesense
