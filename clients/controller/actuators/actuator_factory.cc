#include "clients/controller/actuators/actuator_factory.h"

#include <stdexcept>

#include "clients/controller/actuators/canopen_driver.h"
#include "clients/controller/actuators/serial_driver.h"
#include "clients/controller/actuators/socketcan_bus.h"

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
    // This library has no LCM; the controller client makes that driver.
    throw std::invalid_argument(
        "actuators: driver rig talks LCM; make it with the controller client's "
        "MakeControllerDriver (clients/controller/rig_plant_driver.h)");
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
