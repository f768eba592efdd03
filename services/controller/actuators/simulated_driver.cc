#include "services/controller/actuators/simulated_driver.h"

#include <cmath>
#include <stdexcept>

#include "runtime/devices/device_clock.h"

namespace shapesense {

SimulatedActuatorDriver::SimulatedActuatorDriver(int axes, SimulatedActuatorOptions options,
                                                 TendonPlantCallback plant, MicrosecondClock clock)
    : options_(options),
      plant_(std::move(plant)),
      clock_(clock ? std::move(clock) : MicrosecondClock(EpochMicros)),
      targets_(static_cast<size_t>(std::max(axes, 0)), 0.0),
      actual_(targets_) {
  if (const std::string error = options_.Validate(); !error.empty()) {
    throw std::invalid_argument("simulated actuator: " + error);
  }
  if (axes < 1) throw std::invalid_argument("simulated actuator: expected at least one tendon");
  last_utime_ = clock_();
}

void SimulatedActuatorDriver::Advance() {
  const int64_t now = clock_();
  const double dt = static_cast<double>(std::max<int64_t>(0, now - last_utime_)) * 1e-6;
  last_utime_ = std::max(last_utime_, now);
  // The exact step of x' = (u - x) / tau for a command held since the last call.
  const double follow =
      options_.time_constant_s > 0.0 ? 1.0 - std::exp(-dt / options_.time_constant_s) : 1.0;
  for (size_t i = 0; i < actual_.size(); ++i) actual_[i] += follow * (targets_[i] - actual_[i]);
  health_.last_contact_utime = last_utime_;
  if (plant_) plant_(actual_, last_utime_);
}

void SimulatedActuatorDriver::RequireState(bool allow_fault, const char* action) const {
  if (status_.ok() || (allow_fault && status_.state == ActuatorState::kFault)) return;
  throw ActuatorError(std::string("simulated tendons: ") + action + " refused while " +
                      ActuatorStateName(status_.state) + " (" + status_.reason +
                      "); Connect() first");
}

void SimulatedActuatorDriver::Connect() {
  Advance();
  targets_ = actual_;  // hold where the tendons are
  status_ = {ActuatorState::kOk, "", 0};
  ++health_.connects;
}

void SimulatedActuatorDriver::Disconnect() {
  Stop();
  status_ = {ActuatorState::kDisconnected, "simulated tendons: disconnected by the controller", 0};
}

void SimulatedActuatorDriver::CommandTargets(std::span<const double> target_mm) {
  RequireState(/*allow_fault=*/false, "target");
  if (target_mm.size() != targets_.size()) {
    throw ActuatorError("simulated tendons: expected " + std::to_string(targets_.size()) +
                        " targets, got " + std::to_string(target_mm.size()));
  }
  for (const double mm : target_mm) {
    if (!std::isfinite(mm)) throw ActuatorError("simulated tendons: a target is not a number");
  }
  Advance();  // the old command acted until now
  targets_.assign(target_mm.begin(), target_mm.end());
}

ActuatorPositions SimulatedActuatorDriver::ReadPositions() {
  RequireState(/*allow_fault=*/true, "position read");
  Advance();
  return {actual_, last_utime_};
}

ActuatorStatus SimulatedActuatorDriver::Status() {
  if (status_.state != ActuatorState::kDisconnected) Advance();
  return status_;
}

void SimulatedActuatorDriver::Stop() {
  if (status_.state == ActuatorState::kDisconnected) return;
  Advance();
  targets_ = actual_;
}

ActuatorHealth SimulatedActuatorDriver::Health() {
  health_.link_alive = status_.state != ActuatorState::kDisconnected;
  return health_;
}

void SimulatedActuatorDriver::CutLink(const std::string& reason) {
  // The tendons hold, as a real actuator's link watchdog makes them.
  Advance();
  targets_ = actual_;
  status_ = {ActuatorState::kDisconnected, "simulated tendons: " + reason, 0};
}

void SimulatedActuatorDriver::InjectFault(uint32_t code, const std::string& reason) {
  Advance();
  targets_ = actual_;  // a faulted actuator stops
  status_ = {ActuatorState::kFault, "simulated tendons: " + reason, code};
}

}  // namespace shapesense
