#pragma once

// A stand-in for the virtual rig's plant side, for the controller's tests:
// a peer on the LCM bus that runs the tendon plant (libs/sim/tendon_plant.h)
// on the commands of SHAPESENSE_PLANT_COMMAND, publishes the actuators'
// state on SHAPESENSE_PLANT_STATE, and senses the plant: shape_t with the
// plant's true q plus noise, at a frame rate, a latency after its trigger.
// The link can be cut and the sensing stopped. Time is the given clock.

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <random>
#include <vector>

#include "libs/geometry/types.h"
#include "libs/sim/tendon_plant.h"
#include "runtime/lcm/lcm_bus.h"
#include "services/controller/actuators/simulated_driver.h"
#include "shapesense/shape_t.hpp"
#include "shapesense/tendon_command_t.hpp"

namespace shapesense::testing {

struct FakeRigOptions {
  TendonPlantOptions plant;
  double sensing_period = 1.0 / 30.0;  // s
  double latency = 0.06;               // trigger to publication, s
  double curvature_noise = 1e-5;       // std of the sensed kappa, 1/mm (~0.13 mm at the tip)
  double strain_noise = 2e-5;          // std of the sensed eps0, eps1
  uint32_t seed = 1;
};

class FakeRigPlant {
 public:
  // The actuators start at `initial` (mm).
  FakeRigPlant(LcmBus& bus, const ManipulatorOptions& nominal, const FakeRigOptions& options,
               MicrosecondClock clock, const Eigen::VectorXd& initial);

  // Publishes the actuators' state (unless the link is cut), takes a sample
  // when one is due (unless the sensing is stopped) and publishes the
  // samples whose latency has passed.
  void Tick();

  // false: the link is cut both ways (no state goes out, commands are lost).
  void set_answering(bool answering) { answering_ = answering; }
  // false: no more samples are taken (those in flight still arrive).
  void set_sensing(bool sensing) { sensing_ = sensing; }

  const TendonPlant& plant() const { return plant_; }
  Vec3 TrueTip() const { return plant_.BaseFromTip().translation(); }
  int64_t moves() const { return moves_; }  // commands carried out
  int64_t stops() const { return stops_; }  // MODE_STOP received
  int64_t last_trigger_utime() const { return last_trigger_utime_; }

 private:
  void OnCommand(const tendon_command_t& command);
  void PublishState(int64_t now);
  void Sample(int64_t now);

  LcmBus& bus_;
  TendonPlant plant_;
  FakeRigOptions options_;
  MicrosecondClock clock_;
  std::mt19937_64 rng_;
  bool answering_ = true;
  bool sensing_ = true;
  int64_t next_sample_utime_ = 0;
  int64_t last_trigger_utime_ = 0;
  int64_t trigger_seq_ = 0;
  int64_t seq_ = 0;
  int64_t moves_ = 0;
  int64_t stops_ = 0;
  std::deque<shape_t> in_flight_;
};

}  // namespace shapesense::testing
