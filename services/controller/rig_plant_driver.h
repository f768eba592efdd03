#pragma once

// The actuator driver of the virtual rig (`driver: rig`): the tendons of the
// rig simulator's plant (libs/sim/tendon_plant.h), reached over LCM. It lives
// outside services/controller/actuators, which has no LCM.
//
// The link (docs/controller.md, "The virtual rig's plant link"):
//   driver → plant, SHAPESENSE_PLANT_COMMAND, tendon_command_t: the target
//     displacements (mode MODE_OPEN_LOOP: the plant does not care which law
//     computed them); MODE_STOP: hold the actuators where they stand
//     (displacement_mm then carries the last positions the driver saw).
//   plant → driver, SHAPESENSE_PLANT_STATE, tendon_state_t, at the plant's own
//     rate (several times per state_timeout_s): the actuators' positions, the
//     plant's tensions and fault bits. FAULT_LINK and FAULT_DRIVE are faults of
//     the plant's actuators; FAULT_SLACK and FAULT_LIMIT only inform.
// No state for rig.state_timeout_s (on the driver's clock) is a lost link.
//
// One thread: the bus is handled by its owner's loop, where the driver's
// subscription keeps the latest state; only Connect() handles the bus itself,
// while it waits for the plant's first state.

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "runtime/lcm/lcm_bus.h"
#include "services/controller/actuators/actuator_driver.h"
#include "services/controller/actuators/actuator_options.h"
#include "services/controller/actuators/simulated_driver.h"

namespace shapesense {

class RigPlantDriver : public ActuatorDriver {
 public:
  // Subscribes to the plant's state on `bus` (which must outlive every use of
  // the driver; the subscription itself is safe to outlive the driver).
  // `clock`: µs since the epoch for the link's timeout (empty: the host clock).
  RigPlantDriver(LcmBus& bus, int axes, const RigActuatorOptions& options,
                 MicrosecondClock clock = {});

  int axis_count() const override { return axes_; }
  std::string description() const override;
  void Connect() override;
  void Disconnect() override;
  void CommandTargets(std::span<const double> target_mm) override;
  ActuatorPositions ReadPositions() override;
  ActuatorStatus Status() override;
  void Stop() override;
  ActuatorHealth Health() override;

 private:
  // What the subscription keeps: the plant's latest state (shared with the
  // callback, so that it stays valid whichever goes first).
  struct Inbox {
    std::vector<double> positions;
    std::vector<int32_t> faults;
    int64_t received_utime = 0;  // on the driver's clock
    int64_t count = 0;
  };

  // Looks at the latest state: faults, a wrong size, a lost link.
  void Refresh();
  void RequireState(bool allow_fault, const char* action) const;
  bool Publish(std::span<const double> mm, int8_t mode);
  std::string CheckState() const;

  LcmBus& bus_;
  const int axes_;
  const RigActuatorOptions options_;
  MicrosecondClock clock_;
  std::shared_ptr<Inbox> inbox_;
  std::vector<double> positions_;
  int64_t seq_ = 0;
  ActuatorStatus status_{ActuatorState::kDisconnected, "rig: not connected yet", 0};
  ActuatorHealth health_;
};

// The driver `options.driver` names, not yet connected: rig over `bus`,
// every other kind by MakeActuatorDriver (actuators/actuator_factory.h; the
// simulated one with `clock` and no plant). Throws std::invalid_argument on
// options that fail Validate().
std::unique_ptr<ActuatorDriver> MakeControllerDriver(const ActuatorOptions& options, LcmBus& bus,
                                                     MicrosecondClock clock = {});

}  // namespace shapesense
