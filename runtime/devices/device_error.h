#pragma once

#include <stdexcept>

namespace shapesense {

// A device link could not be opened, was lost, or the device refused or
// faulted: a serial port, a CAN interface, an actuator behind either. The
// message names the device (port, CAN interface and node) and the cause.
class ActuatorError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace shapesense
