#pragma once

// One interface for every tendon actuator the controller can drive: a serial
// line protocol (docs/actuators.md), CANopen CiA 402 drives on SocketCAN, and
// the virtual rig's simulated tendons. Chosen by ActuatorOptions::driver
// (actuator_factory.h).
//
// Safety limits are not the drivers' business (a safety gate sits in front of
// every driver), but one rule is: after a fault or a lost link a driver sends
// no target until Connect() is called again. Stop commands are the exception.

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "runtime/devices/device_error.h"

namespace shapesense {

enum class ActuatorState {
  kDisconnected,  // never connected, or the link was lost: Connect() to resume
  kOk,            // accepts targets
  kFault,         // the actuator reported a fault: Connect() resets it
};

// "disconnected", "ok" or "fault".
const char* ActuatorStateName(ActuatorState state);

struct ActuatorStatus {
  ActuatorState state = ActuatorState::kDisconnected;
  // Why the state is not ok, e.g. "node 2: EMCY 0x7500 (communication error)"
  // or "/dev/ttyUSB0: link cut (hang-up)". Empty when ok.
  std::string reason;
  // The device's own code for a fault when it gave one (a CANopen EMCY error
  // code, the serial protocol's fault code); 0 otherwise.
  uint32_t code = 0;

  bool ok() const { return state == ActuatorState::kOk; }
};

// Actual tendon displacements, mm, in axis order, and when they were sampled.
struct ActuatorPositions {
  std::vector<double> mm;
  int64_t utime = 0;  // µs since the epoch (host clock)
};

// Link counters for monitoring; they only grow (but link_alive and round_trip_us).
struct ActuatorHealth {
  bool link_alive = false;         // the last exchange with every device succeeded
  int64_t last_contact_utime = 0;  // the last reply or frame from the actuator
  int64_t round_trip_us = 0;    // the last request → reply (serial: one line; CAN: SYNC → PDOs)
  int64_t corrupt_replies = 0;  // replies rejected: bad checksum or malformed
  int64_t rejected_requests = 0;  // requests the device refused (e.g. a checksum error there)
  int64_t timeouts = 0;           // replies that did not come in time
  int64_t retries = 0;            // requests sent again after a timeout or a rejection
  int64_t connects = 0;           // successful Connect() calls
};

// Threads: one thread drives an ActuatorDriver (the controller loop); the
// drivers are not thread-safe.
class ActuatorDriver {
 public:
  virtual ~ActuatorDriver() = default;

  // Tendons (axes) this driver commands.
  virtual int axis_count() const = 0;
  // What the driver talks to, for messages: "serial /dev/ttyUSB0", "socketcan can0", ...
  virtual std::string description() const = 0;

  // Opens the link and brings every axis to accepting targets, holding where
  // it stands. Also the explicit reset after a fault or a lost link: it starts
  // from scratch. Throws ActuatorError naming the device and the cause.
  virtual void Connect() = 0;
  // Stops every axis (best effort) and closes the link. Never throws.
  virtual void Disconnect() = 0;

  // New target displacement per axis, mm (axis_count() values). Throws
  // ActuatorError without sending anything when the state is not ok, and when
  // the link fails or the actuator faults on the way (the driver then stops
  // what it can still reach and the state says why).
  virtual void CommandTargets(std::span<const double> target_mm) = 0;
  // Actual positions now. Works in a fault (diagnosis) while the link is up;
  // throws ActuatorError when disconnected or the link fails.
  virtual ActuatorPositions ReadPositions() = 0;
  // The state after looking at what the actuator said since the last call
  // (faults, heartbeats). Never throws.
  virtual ActuatorStatus Status() = 0;
  // Every axis holds where it is (serial X; CiA 402 halt). The driver stays
  // connected and a later CommandTargets moves again. Never throws.
  virtual void Stop() = 0;
  virtual ActuatorHealth Health() = 0;
};

}  // namespace shapesense
