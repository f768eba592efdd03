#include "libs/control/safety_gate.h"

#include "libs/core/error.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace shapesense {
namespace {

// Added above the floor when raising, N: rounding in C_m^-1 y stays below it.
constexpr double kTensionMargin = 1e-9;
// A raise smaller than this is rounding, not worth reporting, N.
constexpr double kReportableRaise = 1e-6;

GateResult Hold(const GateInput& input, uint32_t reasons) {
  return GateResult{input.previous, reasons, true};
}

// Per tendon, the lower of the minimum tension and the previous command's
// own: a command below the floor may not go lower (it heals), one above may
// not drop below it.
Eigen::VectorXd TensionFloor(const SafetyEnvelope& envelope, const Eigen::VectorXd& previous) {
  return envelope.Tensions(previous).cwiseMin(envelope.limits().min_tension);
}

bool MeetsFloor(const SafetyEnvelope& envelope, const Eigen::VectorXd& command,
                const Eigen::VectorXd& floor) {
  return (envelope.Tensions(command) - floor).minCoeff() >= 0.0;
}

// The range, widened to take in the previous command if it lies outside.
std::pair<Eigen::VectorXd, Eigen::VectorXd> WidenedRange(const SafetyEnvelope& envelope,
                                                         const Eigen::VectorXd& previous) {
  return {envelope.low().cwiseMin(previous), envelope.high().cwiseMax(previous)};
}

// Largest t in [0, 1] with the tensions of previous + t (command - previous)
// at or above the floor (tensions are linear along the segment).
double LargestStepMeetingFloor(const SafetyEnvelope& envelope, const Eigen::VectorXd& previous,
                               const Eigen::VectorXd& command, const Eigen::VectorXd& floor) {
  const Eigen::VectorXd from = envelope.Tensions(previous);
  const Eigen::VectorXd to = envelope.Tensions(command);
  double t = 1.0;
  for (int i = 0; i < from.size(); ++i) {
    if (to(i) < floor(i)) t = std::min(t, std::max(0.0, from(i) - floor(i)) / (from(i) - to(i)));
  }
  return t;
}

// previous + t (command - previous), kept in the widened range against
// rounding; falls back to a shorter step and at last to previous itself if
// rounding leaves a tension a hair below the floor.
Eigen::VectorXd StepAlong(const SafetyEnvelope& envelope, const Eigen::VectorXd& previous,
                          const Eigen::VectorXd& command, double t, const Eigen::VectorXd& floor) {
  if (t == 1.0 && MeetsFloor(envelope, command, floor)) return command;
  const auto [low, high] = WidenedRange(envelope, previous);
  for (int attempt = 0; attempt < 4 && t > 0.0; ++attempt, t *= 0.5) {
    const Eigen::VectorXd step = (previous + t * (command - previous)).cwiseMax(low).cwiseMin(high);
    if (MeetsFloor(envelope, step, floor)) return step;
  }
  return previous;
}

// Steps 5-8 of the gate (safety_gate.h).
GateResult MoveWithinEnvelope(const SafetyEnvelope& envelope, const GateInput& input) {
  const SafetyLimits& limits = envelope.limits();
  GateResult result;
  Eigen::VectorXd target = input.proposal.cwiseMax(envelope.low()).cwiseMin(envelope.high());
  if (target != input.proposal) result.reasons |= kGateClampedToRange;
  double added_tension = 0.0;
  target = envelope.RaiseTensions(target, limits.min_tension, &added_tension);
  if (added_tension > kReportableRaise) result.reasons |= kGateRaisedForTension;
  const Eigen::VectorXd clamped = target.cwiseMax(envelope.low()).cwiseMin(envelope.high());
  if (clamped != target) result.reasons |= kGateClampedToRange;

  const Eigen::VectorXd delta = clamped - input.previous;
  const double max_step = limits.max_rate * std::min(input.dt, limits.max_step_period);
  const double largest = delta.cwiseAbs().maxCoeff();
  double t = 1.0;
  if (largest > max_step) {
    t = max_step / largest;
    result.reasons |= kGateRateLimited;
  }
  const Eigen::VectorXd floor = TensionFloor(envelope, input.previous);
  const double t_floor = LargestStepMeetingFloor(envelope, input.previous, clamped, floor);
  if (t_floor < t) {
    t = t_floor;
    result.reasons |= kGateTensionLimited;
  }
  result.command = StepAlong(envelope, input.previous, clamped, t, floor);
  return result;
}

}  // namespace

std::string DescribeGateReasons(uint32_t reasons) {
  static constexpr std::array<std::pair<GateReason, const char*>, 11> kNames = {{
      {kGateInvalidProposal, "invalid proposal"},
      {kGateEmergencyStop, "emergency stop"},
      {kGateSensingLost, "sensing lost"},
      {kGateAwaitingSensing, "awaiting sensing"},
      {kGateSensingStale, "sensing stale"},
      {kGateInvalidPeriod, "invalid period"},
      {kGateStoppedUntilRearmed, "stopped until re-armed"},
      {kGateClampedToRange, "clamped to range"},
      {kGateRaisedForTension, "raised for tension"},
      {kGateRateLimited, "rate limited"},
      {kGateTensionLimited, "tension limited"},
  }};
  std::string out;
  for (const auto& [reason, name] : kNames) {
    if ((reasons & reason) == 0) continue;
    if (!out.empty()) out += ", ";
    out += name;
  }
  return out;
}

SafetyEnvelope::SafetyEnvelope(const TendonModel& model, const SafetyLimits& limits)
    : limits_(limits) {
  const int n = model.num_tendons();
  if (const std::string error = limits.ValidateFor(n); !error.empty()) {
    throw std::invalid_argument("safety limits: " + error);
  }
  low_.resize(n);
  high_.resize(n);
  for (int i = 0; i < n; ++i) {
    low_(i) = limits.RangeOf(i).min;
    high_(i) = limits.RangeOf(i).max;
  }
  tension_of_displacement_ =
      model.displacement_compliance().ldlt().solve(Eigen::MatrixXd::Identity(n, n));
  // Straight with every tendon at >= 1 N: tensions that bend nothing.
  const InverseSolution pretension = model.InverseWithMinimumTension(Configuration::Zero(), 1.0);
  pretension_displacements_ = pretension.displacements;
  pretension_tensions_ = Tensions(pretension_displacements_);
  if (!pretension.feasible || pretension_tensions_.minCoeff() < 0.5) {
    throw std::logic_error("safety envelope: no pretension direction for this layout");
  }
  double unused = 0.0;
  resting_ =
      RaiseTensions(pretension_displacements_ * limits.min_tension, limits.min_tension, &unused);
  if (!Check(resting_).empty()) resting_.resize(0);
}

Eigen::VectorXd SafetyEnvelope::Tensions(const Eigen::VectorXd& displacements) const {
  return tension_of_displacement_ * displacements;
}

Eigen::VectorXd SafetyEnvelope::RaiseTensions(const Eigen::VectorXd& displacements, double floor,
                                              double* added_tension) const {
  const Eigen::VectorXd tensions = Tensions(displacements);
  *added_tension = 0.0;
  if ((tensions.array() >= floor).all()) return displacements;
  // Along the pretension direction tendon i gains alpha * w_i of tension.
  const double alpha =
      ((floor - tensions.array()) / pretension_tensions_.array()).maxCoeff() + kTensionMargin;
  *added_tension = alpha * pretension_tensions_.minCoeff();
  return displacements + alpha * pretension_displacements_;
}

Eigen::VectorXd SafetyEnvelope::WithLeastTension(const Eigen::VectorXd& displacements,
                                                 double least) const {
  const double alpha =
      ((least - Tensions(displacements).array()) / pretension_tensions_.array()).maxCoeff();
  return displacements + alpha * pretension_displacements_;
}

std::string SafetyEnvelope::Check(const Eigen::VectorXd& displacements) const {
  if (displacements.size() != num_tendons()) {
    return "expected " + std::to_string(num_tendons()) + " displacements, got " +
           std::to_string(displacements.size());
  }
  if (!displacements.allFinite()) return "displacements: expected finite numbers";
  const Eigen::VectorXd tensions = Tensions(displacements);
  for (int i = 0; i < num_tendons(); ++i) {
    const std::string tendon = "tendon " + std::to_string(i) + ": ";
    if (displacements(i) < low_(i) || displacements(i) > high_(i)) {
      return tendon + Number(displacements(i)) + " mm outside its range [" + Number(low_(i)) +
             ", " + Number(high_(i)) + "] mm";
    }
    if (tensions(i) < limits_.min_tension) {
      return tendon + "tension " + Number(tensions(i)) + " N below the minimum " +
             Number(limits_.min_tension) + " N";
    }
  }
  return "";
}

GateResult GateCommand(const SafetyEnvelope& envelope, const WatchdogOptions& watchdog,
                       const GateInput& input) {
  if (input.previous.size() != envelope.num_tendons() || !input.previous.allFinite()) {
    throw std::invalid_argument("safety gate: the previous command must hold " +
                                std::to_string(envelope.num_tendons()) + " finite displacements");
  }
  if (input.proposal.size() != envelope.num_tendons() || !input.proposal.allFinite()) {
    return Hold(input, kGateInvalidProposal);
  }
  if (input.emergency_stop) return Hold(input, kGateEmergencyStop);
  if (watchdog.enabled) {
    // Written so that a NaN age counts as lost.
    if (!(input.sensing_age < watchdog.lost_age)) return Hold(input, kGateSensingLost);
    if (input.sensing_age >= watchdog.hold_age) return Hold(input, kGateSensingStale);
  }
  if (!(input.dt > 0.0) || !std::isfinite(input.dt)) return Hold(input, kGateInvalidPeriod);
  return MoveWithinEnvelope(envelope, input);
}

SafetyGate::SafetyGate(const TendonModel& model, const SafetyLimits& limits,
                       const WatchdogOptions& watchdog, const Eigen::VectorXd& initial)
    : envelope_(model, limits), watchdog_(watchdog), command_(initial) {
  if (initial.size() != envelope_.num_tendons() || !initial.allFinite()) {
    throw std::invalid_argument("safety gate: the initial command must hold " +
                                std::to_string(envelope_.num_tendons()) + " finite displacements");
  }
}

GateResult SafetyGate::Apply(const Eigen::VectorXd& proposal, double dt, double sensing_age,
                             bool emergency_stop) {
  last_emergency_stop_ = emergency_stop;
  last_sensing_fresh_ = !watchdog_.enabled || sensing_age < watchdog_.hold_age;
  const GateInput input{proposal, command_, dt, sensing_age, emergency_stop};
  GateResult result = GateCommand(envelope_, watchdog_, input);
  if (result.has(kGateSensingLost) && !had_sensing_) {
    // Nothing sensed since start: wait for it, there is nothing to have lost.
    result.reasons = (result.reasons & ~kGateSensingLost) | kGateAwaitingSensing;
  }
  if (stopped_ && !result.held) {
    // A stop latched earlier holds until Rearm(), whatever this input says.
    result = GateResult{command_, kGateStoppedUntilRearmed, true};
  } else if (stopped_) {
    result.reasons |= kGateStoppedUntilRearmed;
  }
  if (result.has(kGateEmergencyStop) || result.has(kGateSensingLost)) stopped_ = true;
  if (last_sensing_fresh_) had_sensing_ = true;
  command_ = result.command;
  return result;
}

std::string SafetyGate::Rearm() {
  if (last_emergency_stop_) return "the emergency stop is engaged";
  if (!last_sensing_fresh_) return "the sensing is not fresh";
  stopped_ = false;
  return "";
}

}  // namespace shapesense
