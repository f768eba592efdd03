#pragma once

// The simulated actuator driver of the virtual rig: it holds the commanded
// displacements, lets each tendon follow its command through a first-order
// lag (time constant simulated.time_constant_s, exact for any step between
// calls) and hands the tendons' displacements to a plant callback, which is
// where the virtual rig's tendon plant (libs/sim) plugs in. Faults and a cut
// link can be injected for tests of the controller.

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "services/controller/actuators/actuator_driver.h"
#include "services/controller/actuators/actuator_options.h"

namespace shapesense {

// Receives the tendons' actual displacements (mm, axis order) at `utime`,
// every time the driver advances them.
using TendonPlantCallback =
    std::function<void(std::span<const double> displacement_mm, int64_t utime)>;
// µs since the epoch; the driver's only notion of time.
using MicrosecondClock = std::function<int64_t()>;

class SimulatedActuatorDriver : public ActuatorDriver {
 public:
  // An empty `clock` is the host clock.
  SimulatedActuatorDriver(int axes, SimulatedActuatorOptions options,
                          TendonPlantCallback plant = {}, MicrosecondClock clock = {});

  int axis_count() const override { return static_cast<int>(actual_.size()); }
  std::string description() const override { return "simulated tendons"; }
  void Connect() override;
  void Disconnect() override;
  void CommandTargets(std::span<const double> target_mm) override;
  ActuatorPositions ReadPositions() override;
  ActuatorStatus Status() override;
  void Stop() override;
  ActuatorHealth Health() override;

  // As if the link were cut / the actuator faulted: Connect() recovers.
  void CutLink(const std::string& reason);
  void InjectFault(uint32_t code, const std::string& reason);
  const std::vector<double>& targets() const { return targets_; }

 private:
  // Moves every tendon along its lag up to now and tells the plant.
  void Advance();
  void RequireState(bool allow_fault, const char* action) const;

  const SimulatedActuatorOptions options_;
  TendonPlantCallback plant_;
  MicrosecondClock clock_;
  std::vector<double> targets_;
  std::vector<double> actual_;
  int64_t last_utime_ = 0;
  ActuatorStatus status_{ActuatorState::kDisconnected, "not connected yet", 0};
  ActuatorHealth health_;
};

}  // namespace shapesense
