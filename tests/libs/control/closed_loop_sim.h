#pragma once

// An in-process closed loop for the tests: plant (libs/sim/tendon_plant.h)
// → sensed configuration with noise, a sampling period and latency →
// controller → safety gate → plant. No rendering, no clocks: simulated time.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <deque>
#include <memory>
#include <random>
#include <vector>

#include "libs/control/controllers.h"
#include "libs/control/limit_audit.h"
#include "libs/control/safety_gate.h"
#include "libs/mechanics/configuration_geometry.h"
#include "libs/sim/tendon_plant.h"

namespace shapesense::testing {

struct LoopOptions {
  double dt = 0.01;                    // control period, s
  double sensing_period = 1.0 / 30.0;  // camera frame-sets, s
  double latency = 0.06;               // from trigger to the controller, s
  double curvature_noise = 1e-5;       // std of the sensed kappa, 1/mm (~0.13 mm at the tip)
  double strain_noise = 2e-5;          // std of the sensed eps0, eps1
  double hold_time = 8.0;              // per target, s
  double measure_time = 1.0;           // steady state: the last this many seconds of each hold
  // Sensing stops for good at this time (s from the start; < 0: never).
  double sensing_stops_at = -1.0;
  uint32_t seed = 1;
};

struct TargetOutcome {
  double mean_tip_error = 0.0;  // over the measuring window, mm
  double max_tip_error = 0.0;
  // The tip relative to the distal section's start: what is left once the
  // proximal compression eps0, which no controller can set on its own, is
  // taken out, mm.
  double mean_distal_tip_error = 0.0;
};

struct LoopResult {
  std::vector<TargetOutcome> targets;
  LimitViolations violations;  // of every command, by LimitAudit
  int steps = 0;
  // Time of the last command that moved, s (for the sensing-loss test).
  double last_motion_time = 0.0;
  uint32_t reasons_seen = 0;
};

inline Vec3 DistalTip(const Configuration& q, const TendonModel& model) {
  return BaseFromTip(q, model.lengths()).translation() -
         BaseFromDistalStart(q, model.lengths()).translation();
}

// Samples the plant each sensing period and hands each sample over `latency` later.
class SimulatedSensing {
 public:
  SimulatedSensing(const LoopOptions& options) : options_(options), rng_(options.seed) {}

  void Step(double time, const Configuration& truth) {
    const bool stopped = options_.sensing_stops_at >= 0.0 && time >= options_.sensing_stops_at;
    if (!stopped && time + 1e-9 >= next_sample_) {
      next_sample_ += options_.sensing_period;
      std::normal_distribution<double> kappa(0.0, options_.curvature_noise);
      std::normal_distribution<double> strain(0.0, options_.strain_noise);
      SensedConfiguration sample;
      sample.configuration =
          truth + Configuration(kappa(rng_), kappa(rng_), strain(rng_), strain(rng_));
      sample.time = time;
      sample.valid = true;
      pending_.push_back(sample);
    }
    while (!pending_.empty() && pending_.front().time + options_.latency <= time + 1e-9) {
      latest_ = pending_.front();
      pending_.pop_front();
    }
  }
  const SensedConfiguration& latest() const { return latest_; }

 private:
  LoopOptions options_;
  std::mt19937_64 rng_;
  double next_sample_ = 0.0;
  std::deque<SensedConfiguration> pending_;
  SensedConfiguration latest_;
};

// Runs the targets one after another, each held for options.hold_time.
inline LoopResult RunLoop(const ManipulatorOptions& nominal,
                          const TendonPlantOptions& plant_options,
                          const ControllerOptions& controller_options,
                          const std::vector<Configuration>& targets, const LoopOptions& options) {
  const TendonModel model(nominal);
  SafetyGate gate(model, controller_options.limits, controller_options.watchdog,
                  SafetyEnvelope(model, controller_options.limits).RestingCommand());
  TendonPlant plant(nominal, plant_options, gate.command());
  const std::unique_ptr<Controller> controller = MakeController(model, controller_options);
  SimulatedSensing sensing(options);
  LimitAudit audit(gate.envelope());
  audit.Check(gate.command(), 0);
  LoopResult result;
  const int steps_per_target = static_cast<int>(std::lround(options.hold_time / options.dt));
  const int measured_steps = static_cast<int>(std::lround(options.measure_time / options.dt));
  double time = 0.0;
  for (const Configuration& target : targets) {
    const Vec3 target_tip = BaseFromTip(target, model.lengths()).translation();
    TargetOutcome outcome;
    for (int step = 0; step < steps_per_target; ++step) {
      sensing.Step(time, plant.configuration());
      time += options.dt;
      ControlInput input;
      input.time = time;
      input.dt = options.dt;
      input.target = target;
      input.sensed = sensing.latest();
      input.last_command = gate.command();
      const Eigen::VectorXd previous = gate.command();
      const GateResult gated =
          gate.Apply(controller->Propose(input), options.dt, input.sensing_age(), false);
      audit.Check(gated.command, std::llround(time * 1e6));
      result.reasons_seen |= gated.reasons;
      if (gated.command != previous) result.last_motion_time = time;
      plant.Command(gated.command);
      ++result.steps;
      if (step >= steps_per_target - measured_steps) {
        const double error = (plant.BaseFromTip().translation() - target_tip).norm();
        outcome.mean_tip_error += error / measured_steps;
        outcome.max_tip_error = std::max(outcome.max_tip_error, error);
        outcome.mean_distal_tip_error +=
            (DistalTip(plant.configuration(), model) - DistalTip(target, model)).norm() /
            measured_steps;
      }
    }
    result.targets.push_back(outcome);
  }
  result.violations = audit.violations();
  return result;
}

inline double MeanOf(const std::vector<TargetOutcome>& outcomes) {
  double sum = 0.0;
  for (const TargetOutcome& o : outcomes) sum += o.mean_tip_error;
  return sum / static_cast<double>(outcomes.size());
}

inline double MeanDistalOf(const std::vector<TargetOutcome>& outcomes) {
  double sum = 0.0;
  for (const TargetOutcome& o : outcomes) sum += o.mean_distal_tip_error;
  return sum / static_cast<double>(outcomes.size());
}

inline double MaxOf(const std::vector<TargetOutcome>& outcomes) {
  double worst = 0.0;
  for (const TargetOutcome& o : outcomes) worst = std::max(worst, o.max_tip_error);
  return worst;
}

}  // namespace shapesense::testing
