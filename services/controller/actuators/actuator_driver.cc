#include "services/controller/actuators/actuator_driver.h"

namespace shapesense {

const char* ActuatorStateName(ActuatorState state) {
  switch (state) {
    case ActuatorState::kDisconnected:
      return "disconnected";
    case ActuatorState::kOk:
      return "ok";
    case ActuatorState::kFault:
      return "fault";
  }
  return "unknown";
}

}  // namespace shapesense
