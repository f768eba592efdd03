#include "services/controller/actuators/actuator_factory.h"

#include <stdexcept>

#include "runtime/devices/socketcan_bus.h"
#include "services/controller/actuators/canopen_driver.h"
#include "services/controller/actuators/serial_driver.h"

namespace shapesense {

std::unique_ptr<ActuatorDriver> MakeActuatorDriver(const ActuatorOptions& options,
                                                   ActuatorDriverContext context) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw std::invalid_argument("actuators: " + error);
  }
  if (options.driver == "serial") {
    return std::make_unique<SerialActuatorDriver>(options.serial, options.tendons);
  }
  if (options.driver == "rig") {
    // This library has no LCM; the controller service makes that driver.
    throw std::invalid_argument(
        "actuators: driver rig talks LCM; make it with the controller service's "
        "MakeControllerDriver (services/controller/rig_plant_driver.h)");
  }
  if (options.driver == "socketcan") {
    const std::string interface = options.canopen.interface;
    return std::make_unique<CanOpenActuatorDriver>(
        options.canopen, [interface] { return OpenSocketCanBus(interface); },
        "socketcan " + interface);
  }
  return std::make_unique<SimulatedActuatorDriver>(
      options.tendons, options.simulated, std::move(context.plant), std::move(context.clock));
}

}  // namespace shapesense
