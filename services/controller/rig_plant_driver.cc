#include "services/controller/rig_plant_driver.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "runtime/devices/device_clock.h"
#include "runtime/lcm/channels.h"
#include "services/controller/actuators/actuator_factory.h"
#include "shapesense/tendon_command_t.hpp"
#include "shapesense/tendon_state_t.hpp"

namespace shapesense {
namespace {

constexpr const char* kName = "rig";
constexpr int32_t kFaultBits =
    int32_t{tendon_state_t::FAULT_LINK} | int32_t{tendon_state_t::FAULT_DRIVE};

std::string Seconds(double seconds) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3f s", seconds);
  return text;
}

}  // namespace

RigPlantDriver::RigPlantDriver(LcmBus& bus, int axes, const RigActuatorOptions& options,
                               MicrosecondClock clock)
    : bus_(bus),
      axes_(axes),
      options_(options),
      clock_(clock ? std::move(clock) : MicrosecondClock(EpochMicros)),
      inbox_(std::make_shared<Inbox>()) {
  if (const std::string error = options_.Validate(); !error.empty()) {
    throw std::invalid_argument("rig actuator: " + error);
  }
  if (axes < 1) throw std::invalid_argument("rig actuator: expected at least one tendon");
  // The callback holds the inbox and the clock, never the driver.
  bus_.Subscribe<tendon_state_t>(
      channels::kPlantState,
      [inbox = inbox_, clock = clock_](tendon_state_t&& state, const std::string&, int64_t) {
        inbox->positions = std::move(state.displacement_mm);
        inbox->faults = std::move(state.fault);
        inbox->received_utime = clock();
        ++inbox->count;
      });
}

std::string RigPlantDriver::description() const { return "rig plant over LCM"; }

std::string RigPlantDriver::CheckState() const {
  if (static_cast<int>(inbox_->positions.size()) != axes_) {
    return "the plant reports " + std::to_string(inbox_->positions.size()) +
           " tendons, the driver has " + std::to_string(axes_);
  }
  for (size_t i = 0; i < inbox_->faults.size(); ++i) {
    if ((inbox_->faults[i] & kFaultBits) != 0) {
      return "the plant reports a fault on tendon " + std::to_string(i) + " (bits " +
             std::to_string(inbox_->faults[i]) + ")";
    }
  }
  for (const double mm : inbox_->positions) {
    if (!std::isfinite(mm)) return "the plant reports a position that is not a number";
  }
  return "";
}

void RigPlantDriver::Refresh() {
  if (status_.state == ActuatorState::kDisconnected) return;
  const double silent_s = static_cast<double>(clock_() - inbox_->received_utime) * 1e-6;
  if (silent_s > options_.state_timeout_s) {
    status_ = {ActuatorState::kDisconnected,
               std::string(kName) + ": link lost: no plant state on " + channels::kPlantState +
                   " for " + Seconds(silent_s) + " (state_timeout_s " +
                   Seconds(options_.state_timeout_s) + ")",
               0};
    ++health_.timeouts;
    return;
  }
  if (status_.state == ActuatorState::kFault) return;  // until Connect()
  if (const std::string why = CheckState(); !why.empty()) {
    status_ = {ActuatorState::kFault, std::string(kName) + ": " + why, 0};
    return;
  }
  positions_ = inbox_->positions;
}

void RigPlantDriver::RequireState(bool allow_fault, const char* action) const {
  if (status_.ok() || (allow_fault && status_.state == ActuatorState::kFault)) return;
  throw ActuatorError(std::string(kName) + ": " + action + " refused while " +
                      ActuatorStateName(status_.state) + " (" + status_.reason +
                      "); Connect() first");
}

bool RigPlantDriver::Publish(std::span<const double> mm, int8_t mode) {
  tendon_command_t command{};
  command.header.seq = seq_++;
  command.header.utime = clock_();
  command.num_tendons = static_cast<int32_t>(mm.size());
  command.displacement_mm.assign(mm.begin(), mm.end());
  command.source_trigger_seq = -1;
  command.mode = mode;
  return bus_.Publish(channels::kPlantCommand, command);
}

void RigPlantDriver::Connect() {
  // Only a state that arrives from now on proves the plant is there.
  const int64_t seen = inbox_->count;
  const int64_t deadline = SteadyMicros() + SecondsToMicros(options_.connect_timeout_s);
  while (inbox_->count == seen && SteadyMicros() < deadline) bus_.Handle(10);
  if (inbox_->count == seen) {
    status_ = {ActuatorState::kDisconnected,
               std::string(kName) + ": cannot connect: no plant state on " + channels::kPlantState +
                   " within " + Seconds(options_.connect_timeout_s) +
                   " (is the virtual rig running?)",
               0};
    throw ActuatorError(status_.reason);
  }
  if (const std::string why = CheckState(); !why.empty()) {
    status_ = {ActuatorState::kDisconnected, std::string(kName) + ": cannot connect: " + why, 0};
    throw ActuatorError(status_.reason);
  }
  positions_ = inbox_->positions;
  status_ = {ActuatorState::kOk, "", 0};
  ++health_.connects;
}

void RigPlantDriver::Disconnect() {
  Stop();
  status_ = {ActuatorState::kDisconnected, std::string(kName) + ": disconnected by the controller",
             0};
}

void RigPlantDriver::CommandTargets(std::span<const double> target_mm) {
  Refresh();
  RequireState(/*allow_fault=*/false, "target");
  if (static_cast<int>(target_mm.size()) != axes_) {
    throw ActuatorError(std::string(kName) + ": expected " + std::to_string(axes_) +
                        " targets, got " + std::to_string(target_mm.size()));
  }
  for (const double mm : target_mm) {
    if (!std::isfinite(mm)) throw ActuatorError(std::string(kName) + ": a target is not a number");
  }
  if (!Publish(target_mm, tendon_command_t::MODE_OPEN_LOOP)) {
    status_ = {
        ActuatorState::kDisconnected,
        std::string(kName) + ": link lost: publishing on " + channels::kPlantCommand + " failed",
        0};
    throw ActuatorError(status_.reason);
  }
}

ActuatorPositions RigPlantDriver::ReadPositions() {
  Refresh();
  RequireState(/*allow_fault=*/true, "position read");
  return {positions_, inbox_->received_utime};
}

ActuatorStatus RigPlantDriver::Status() {
  Refresh();
  return status_;
}

void RigPlantDriver::Stop() {
  if (status_.state == ActuatorState::kDisconnected || positions_.empty()) return;
  Publish(positions_, tendon_command_t::MODE_STOP);  // best effort
}

ActuatorHealth RigPlantDriver::Health() {
  Refresh();
  health_.link_alive = status_.state != ActuatorState::kDisconnected;
  health_.last_contact_utime = inbox_->received_utime;
  return health_;
}

std::unique_ptr<ActuatorDriver> MakeControllerDriver(const ActuatorOptions& options, LcmBus& bus,
                                                     MicrosecondClock clock) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw std::invalid_argument("actuators: " + error);
  }
  if (options.driver == "rig") {
    return std::make_unique<RigPlantDriver>(bus, options.tendons, options.rig, std::move(clock));
  }
  ActuatorDriverContext context;
  context.clock = std::move(clock);
  return MakeActuatorDriver(options, std::move(context));
}

}  // namespace shapesense
