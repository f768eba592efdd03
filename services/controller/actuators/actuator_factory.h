#pragma once

#include <memory>

#include "services/controller/actuators/actuator_driver.h"
#include "services/controller/actuators/actuator_options.h"
#include "services/controller/actuators/simulated_driver.h"

namespace shapesense {

// What a process gives the drivers besides their options.
struct ActuatorDriverContext {
  // simulated: receives the tendons' displacements (the virtual rig's plant).
  TendonPlantCallback plant;
  // simulated: the clock (empty: the host clock).
  MicrosecondClock clock;
};

// The driver `options.driver` names, not yet connected (nothing is opened
// here). Throws std::invalid_argument on options that fail Validate(), and
// for driver rig (it needs LCM: services/controller/rig_plant_driver.h).
std::unique_ptr<ActuatorDriver> MakeActuatorDriver(const ActuatorOptions& options,
                                                   ActuatorDriverContext context = {});

}  // namespace shapesense
