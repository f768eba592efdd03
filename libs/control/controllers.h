#pragma once

// The control laws (docs/control.md). Each turns a target configuration, the
// last sensed configuration and the last command into a proposal of tendon
// displacements, which the caller passes through the safety gate
// (safety_gate.h) before anything moves. No clocks, no I/O: time comes in
// with the input. What they keep between steps (an integral, a Jacobian
// estimate) is their state, read back through accessors for logging.
//
// The controlled quantities are (kappa_x, kappa_z, eps1): eps0 follows eps1
// and is not independently controllable (docs/mechanics.md).

#include <Eigen/Core>
#include <deque>
#include <limits>
#include <memory>
#include <utility>

#include "libs/control/control_options.h"
#include "libs/mechanics/tendon_model.h"

namespace shapesense {

struct SensedConfiguration {
  Configuration configuration = Configuration::Zero();
  // When it was measured (the frame-set's trigger time), on the clock of
  // ControlInput::time, s.
  double time = -std::numeric_limits<double>::infinity();
  bool valid = false;
};

struct ControlInput {
  double time = 0.0;                             // now, s
  double dt = 0.0;                               // since the previous step, s
  Configuration target = Configuration::Zero();  // resolved (targets.h)
  SensedConfiguration sensed;
  // What the gate let through at the previous step (where the actuators are going).
  Eigen::VectorXd last_command;

  double sensing_age() const {
    return sensed.valid ? time - sensed.time : std::numeric_limits<double>::infinity();
  }
};

class Controller {
 public:
  virtual ~Controller() = default;
  // Displacements to propose to the gate, one per tendon, mm.
  virtual Eigen::VectorXd Propose(const ControlInput& input) = 0;
  virtual ControlMode mode() const = 0;
};

// y = the model's inverse of the target, every tendon at >= min_tension.
class OpenLoopController : public Controller {
 public:
  OpenLoopController(const TendonModel& model, const ControllerOptions& options);
  Eigen::VectorXd Propose(const ControlInput& input) override;
  ControlMode mode() const override { return ControlMode::kOpenLoop; }

 private:
  TendonModel model_;
  double min_tension_;
};

// y = the model's inverse of (target + correction), the correction a PI of
// the sensed error. Anti-windup by conditional integration: the integral
// does not grow in the direction of what the model's inverse and the gate
// did not carry out of the last desired configuration (A y_last -
// desired_last, per the model), e.g. while the rate limit holds a move back,
// against a range end, or below an eps1 that the tension floor forbids.
class ClosedLoopController : public Controller {
 public:
  ClosedLoopController(const TendonModel& model, const ControllerOptions& options);
  Eigen::VectorXd Propose(const ControlInput& input) override;
  ControlMode mode() const override { return ControlMode::kClosedLoop; }
  // (kappa_x, kappa_z, eps1).
  const Eigen::Vector3d& integral() const { return integral_; }

 private:
  Eigen::Vector3d Bounded(const Eigen::Vector3d& correction) const;
  Eigen::Vector3d OutsideDeadband(const Eigen::Vector3d& error) const;
  Eigen::Vector3d WithoutWindup(const Eigen::Vector3d& increment,
                                const Eigen::Vector3d& shortfall) const;

  TendonModel model_;
  ControllerOptions options_;
  Eigen::Vector3d integral_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_desired_ = Eigen::Vector3d::Zero();
  bool has_last_ = false;
};

// Model-less (after Yip & Camarillo): J, the Jacobian of the curvatures
// (weighed as tip motion, mm) to the displacements, starts as the model's A
// and is corrected by a Broyden rank-one update from each pair of sensed
// samples, paired with the commands in force when they were measured (so
// sensing latency does not skew it). Step: damped least squares
// dy = J^T (J J^T + damping^2 I)^-1 (gain dt e), added to the last command.
// Which of the redundant ways to pull carries that out, and the pretension
// (which sets eps1 and bends nothing), are not learned: the command is
// re-expressed as the model's minimum-tension inverse of the curvatures the
// model sees in it, at an eps1 moved toward the sensed eps1 error, every
// tension at least min_tension + pretension_margin.
class ModelLessController : public Controller {
 public:
  ModelLessController(const TendonModel& model, const ControllerOptions& options);
  Eigen::VectorXd Propose(const ControlInput& input) override;
  ControlMode mode() const override { return ControlMode::kModelLess; }
  // Rows kappa_x, kappa_z, weighed by L1^2 / 2.
  const Eigen::Matrix2Xd& jacobian() const { return jacobian_; }
  const Eigen::Matrix2Xd& model_jacobian() const { return model_jacobian_; }
  int updates() const { return updates_; }

 private:
  void LearnFromSample(const SensedConfiguration& sensed);
  const Eigen::VectorXd* CommandAt(double time) const;
  Eigen::Vector2d WeighedCurvature(const Configuration& q) const;
  Eigen::VectorXd CurvatureStep(const ControlInput& input) const;
  Eigen::VectorXd WithPretension(const ControlInput& input, const Eigen::VectorXd& command) const;

  TendonModel model_;
  ControllerOptions options_;
  double weight_ = 0.0;  // tip mm per 1/mm of curvature
  Eigen::Matrix2Xd model_jacobian_;
  Eigen::Matrix2Xd jacobian_;
  std::deque<std::pair<double, Eigen::VectorXd>> history_;  // (time sent, command)
  double last_sample_time_ = -std::numeric_limits<double>::infinity();
  Eigen::Vector2d last_sample_ = Eigen::Vector2d::Zero();
  Eigen::VectorXd last_sample_command_;
  int updates_ = 0;
};

// The controller of options.control_mode(). Throws std::invalid_argument when
// the options fail Validate().
std::unique_ptr<Controller> MakeController(const TendonModel& model,
                                           const ControllerOptions& options);

}  // namespace shapesense
