#pragma once

// The safety gate: the one place every tendon command passes before it
// reaches the actuators (docs/control.md). Checks, in this order:
//
//   1. the proposal is well formed (one finite number per tendon), else hold;
//   2. emergency stop: stop;
//   3. sensing watchdog: lost (age >= lost_age) stops, stale (>= hold_age) holds;
//   4. the step period is a positive number, else hold;
//   5. the proposal is clamped to each tendon's displacement range;
//   6. tensions below the minimum are raised along the pretension direction,
//      which tightens every tendon and bends nothing (per the model), and the
//      range is enforced again;
//   7. the step from the previous command toward that is shortened, keeping
//      its direction, so that no tendon moves faster than max_rate;
//   8. if a tension is still below the minimum (only when step 6 had to give
//      back some of its raise at a range limit), the step is shortened
//      further until none is.
//
// Tensions are linear in the displacements, so a step between two commands
// that both meet the tension floor meets it all along: steps 7 and 8 never
// stall at the floor.
//
// Hold and stop both keep the previous command exactly: that is the safe
// state. Moving anywhere without supervision (relaxing the tendons, going
// straight) could drive the tip into what it touches, and relaxing would
// leave tendons slack. A stop also latches: motion resumes only after
// SafetyGate::Rearm().
//
// The set of safe commands (in range, every tension >= the minimum) is
// convex and holds the previous command, so the result always exists. From a
// previous command outside it (a power-up with slack tendons, limits changed
// under a running system) the gate only allows steps that do not take any
// tendon farther out of its range or lower any tension already below the
// minimum, so it heals toward the safe set.

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "libs/control/control_options.h"
#include "libs/mechanics/tendon_model.h"

namespace shapesense {

// Why the gate changed a proposal (bit flags; several can apply to one command).
enum GateReason : uint32_t {
  kGateInvalidProposal = 1u << 0,      // wrong size or not finite: held
  kGateEmergencyStop = 1u << 1,        // stopped, latched
  kGateSensingLost = 1u << 2,          // stopped, latched
  kGateAwaitingSensing = 1u << 3,      // no sensing yet since start: held
  kGateSensingStale = 1u << 4,         // held
  kGateInvalidPeriod = 1u << 5,        // dt not a positive number: held
  kGateStoppedUntilRearmed = 1u << 6,  // an earlier stop is latched
  kGateClampedToRange = 1u << 7,
  kGateRaisedForTension = 1u << 8,  // pretension added to keep every tendon taut
  kGateRateLimited = 1u << 9,
  kGateTensionLimited = 1u << 10,  // step shortened to keep the tension floor
};

// "clamped to range, rate limited", or "" for none.
std::string DescribeGateReasons(uint32_t reasons);

// The set of safe commands for one model and its limits: each tendon's
// range and the tension floor, tensions being C_m^-1 y (the nominal model).
class SafetyEnvelope {
 public:
  // Throws std::invalid_argument when limits.ValidateFor(model) fails.
  SafetyEnvelope(const TendonModel& model, const SafetyLimits& limits);

  int num_tendons() const { return static_cast<int>(low_.size()); }
  const SafetyLimits& limits() const { return limits_; }
  const Eigen::VectorXd& low() const { return low_; }
  const Eigen::VectorXd& high() const { return high_; }
  // The pretension direction: displacements whose tensions (all >= 1 N)
  // bend nothing, per the model.
  const Eigen::VectorXd& pretension_displacements() const { return pretension_displacements_; }
  Eigen::VectorXd Tensions(const Eigen::VectorXd& displacements) const;
  // Adds the least pretension (displacement along the pretension direction,
  // which bends nothing) that brings every tension to at least `floor`, with
  // a margin of 1e-9 N against rounding. *added_tension: the least tension
  // added to any tendon, N (0 when none was needed).
  Eigen::VectorXd RaiseTensions(const Eigen::VectorXd& displacements, double floor,
                                double* added_tension) const;
  // y moved along the pretension direction until its least tension (over
  // the pretension direction's per-tendon share) is exactly `least`: adds or
  // removes pretension, bending nothing (per the model).
  Eigen::VectorXd WithLeastTension(const Eigen::VectorXd& displacements, double least) const;
  // "" when y is safe, else why not ("tendon 2: 7.1 mm above its range max 6.5").
  std::string Check(const Eigen::VectorXd& displacements) const;
  // Straight, every tendon at the minimum tension (the model's inverse):
  // a safe place to start from. Empty when it lies outside the ranges.
  Eigen::VectorXd RestingCommand() const { return resting_; }

 private:
  SafetyLimits limits_;
  Eigen::VectorXd low_, high_;
  Eigen::MatrixXd tension_of_displacement_;   // C_m^-1
  Eigen::VectorXd pretension_tensions_;       // w >= 1, bends nothing
  Eigen::VectorXd pretension_displacements_;  // C_m w
  Eigen::VectorXd resting_;
};

struct GateInput {
  Eigen::VectorXd proposal;  // mm, one per tendon
  Eigen::VectorXd previous;  // the last command the gate let through, mm
  double dt = 0.0;           // since `previous` was commanded, s
  double sensing_age = 0.0;  // since the last valid sensed configuration, s (inf: none)
  bool emergency_stop = false;
};

struct GateResult {
  Eigen::VectorXd command;  // what may be sent
  uint32_t reasons = 0;     // why it differs from the proposal (GateReason)
  bool held = false;        // command == previous because of a hold or stop

  bool has(GateReason reason) const { return (reasons & reason) != 0; }
};

// The gate as a pure function (no latching). Throws std::invalid_argument
// when `previous` does not have one entry per tendon (a caller's bug; a bad
// proposal is held, not thrown).
GateResult GateCommand(const SafetyEnvelope& envelope, const WatchdogOptions& watchdog,
                       const GateInput& input);

// The gate with its state: the last command and the latched stop.
class SafetyGate {
 public:
  // `initial`: where the actuators are (or RestingCommand()). Throws
  // std::invalid_argument on a wrong size or non-finite entries.
  SafetyGate(const TendonModel& model, const SafetyLimits& limits, const WatchdogOptions& watchdog,
             const Eigen::VectorXd& initial);

  GateResult Apply(const Eigen::VectorXd& proposal, double dt, double sensing_age,
                   bool emergency_stop);
  // Clears a latched stop. Refused (the reason returned) while the emergency
  // stop is engaged or the sensing is not fresh, as of the last Apply().
  std::string Rearm();

  bool stopped() const { return stopped_; }
  const Eigen::VectorXd& command() const { return command_; }
  const SafetyEnvelope& envelope() const { return envelope_; }

 private:
  SafetyEnvelope envelope_;
  WatchdogOptions watchdog_;
  Eigen::VectorXd command_;
  bool stopped_ = false;
  bool had_sensing_ = false;
  bool last_emergency_stop_ = false;
  bool last_sensing_fresh_ = false;
};

}  // namespace shapesense
