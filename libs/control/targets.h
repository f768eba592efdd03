#pragma once

// Targets of the controller: timed configurations q or tip positions, from a
// trajectory in YAML or CSV text (reading the file is the caller's job) or
// one at a time from a stream. Every target is checked against the model and
// the limits and resolved to the configuration the model can reach
// (docs/control.md, "Targets").
//
// YAML:
//   interpolation: linear            # or step
//   targets:
//     - {time: 0.0, q: [0.003, 0.0, 0.0, 0.004]}   # kappa_x, kappa_z (1/mm), eps0, eps1
//     - {time: 2.5, tip: [20.0, 755.0, -8.0]}      # mm, base frame
//
// CSV: a header naming the columns, either
//   time,kappa_x,kappa_z,eps0,eps1     or     time,tip_x,tip_y,tip_z
// then one target per line; '#' comments and blank lines are skipped.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "libs/control/control_options.h"
#include "libs/geometry/types.h"
#include "libs/mechanics/tendon_model.h"

namespace shapesense {

enum class TargetKind { kConfiguration, kTipPosition };

struct Target {
  double time = 0.0;  // s from the start of the trajectory
  TargetKind kind = TargetKind::kConfiguration;
  Configuration configuration = Configuration::Zero();  // kConfiguration
  Vec3 tip = Vec3::Zero();                              // kTipPosition, base frame, mm
};

struct Trajectory {
  // Linear: the target moves from one entry to the next in a straight line
  // in q; step: each entry holds until the next one's time.
  bool interpolate = true;
  std::vector<Target> targets;
};

// Throw InputError("source: where: what"): malformed text, a wrong column
// count, a non-finite or missing number, times not increasing. They do not
// check reachability (ResolveTrajectory does).
Trajectory ParseTrajectoryYaml(const std::string& text, const std::string& source);
Trajectory ParseTrajectoryCsv(const std::string& text, const std::string& source);

// A target the model can reach: curvatures as asked; eps1 at least as asked
// (pretension to keep the tendons taut compresses the section, so it can be
// higher); eps0 the one that follows eps1 (it is not independently
// controllable, docs/mechanics.md), the asked one is ignored.
struct ResolvedTarget {
  bool ok = false;
  std::string reason;  // why not, when !ok
  double time = 0.0;
  Configuration configuration = Configuration::Zero();
  Eigen::VectorXd displacements;  // the model's inverse, every tendon >= the minimum tension
  double tip_residual = 0.0;      // tip targets: distance from the asked tip, mm
};

// Checks targets against one model, its safety limits and the workspace bounds.
class TargetResolver {
 public:
  // Throws std::invalid_argument when the options fail Validate() or do not
  // suit the model.
  TargetResolver(const TendonModel& model, const ControllerOptions& options);

  // Never throws: a bad target comes back !ok with the reason (for streamed
  // targets, which are rejected one by one).
  ResolvedTarget Resolve(const Target& target) const;
  double curvature_bound() const;  // 1/mm
  const TendonModel& model() const { return model_; }

 private:
  ResolvedTarget ResolveConfiguration(const Configuration& q) const;
  TendonModel model_;
  ControllerOptions options_;
};

struct ResolvedTrajectory {
  bool interpolate = true;
  std::vector<ResolvedTarget> targets;  // all ok, times increasing
};

// Throws InputError("source: targets[i]: reason") on the first target that
// cannot be reached.
ResolvedTrajectory ResolveTrajectory(const Trajectory& trajectory, const TargetResolver& resolver,
                                     const std::string& source);

// The target configuration at time t (s): the first before it starts, the
// last after it ends. The trajectory must not be empty.
Configuration TargetAt(const ResolvedTrajectory& trajectory, double time);

}  // namespace shapesense
