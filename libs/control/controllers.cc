#include "libs/control/controllers.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <stdexcept>

namespace shapesense {
namespace {

// The closed loop's controlled quantities (kappa_x, kappa_z, eps1).
// What a unit error in (kappa_x, kappa_z, eps1) moves the tip, mm: L1^2 / 2
// for the curvatures, L1 for the strain. Weighs them so that they compare.
Eigen::Vector3d TipWeights(const TendonModel& model) {
  const double distal = model.lengths().distal;
  return {distal * distal / 2.0, distal * distal / 2.0, distal};
}

Eigen::Vector3d Controlled(const Configuration& q) {
  return {q(kKappaX), q(kKappaZ), q(kStrainDistal)};
}

Configuration WithControlled(Configuration q, const Eigen::Vector3d& controlled) {
  q(kKappaX) = controlled(0);
  q(kKappaZ) = controlled(1);
  q(kStrainDistal) = controlled(2);
  return q;
}

// A shortfall below this (tip mm) is rounding: the step was carried out.
constexpr double kCarriedOut = 1e-3;

bool Fresh(const ControlInput& input, const WatchdogOptions& watchdog) {
  return input.sensed.valid && input.sensing_age() < watchdog.hold_age;
}

void CheckOptions(const TendonModel& model, const ControllerOptions& options) {
  std::string error = options.Validate();
  if (error.empty()) error = options.limits.ValidateFor(model.num_tendons());
  if (!error.empty()) throw std::invalid_argument("controller options: " + error);
}

// The proposal when there is nothing better: stay.
Eigen::VectorXd Stay(const ControlInput& input) { return input.last_command; }

}  // namespace

OpenLoopController::OpenLoopController(const TendonModel& model, const ControllerOptions& options)
    : model_(model), min_tension_(options.limits.min_tension) {
  CheckOptions(model, options);
}

Eigen::VectorXd OpenLoopController::Propose(const ControlInput& input) {
  const InverseSolution inverse = model_.InverseWithMinimumTension(input.target, min_tension_);
  return inverse.feasible ? inverse.displacements : Stay(input);
}

ClosedLoopController::ClosedLoopController(const TendonModel& model,
                                           const ControllerOptions& options)
    : model_(model), options_(options) {
  CheckOptions(model, options);
}

Eigen::Vector3d ClosedLoopController::Bounded(const Eigen::Vector3d& correction) const {
  const double max_curvature = options_.closed_loop.max_correction_bend / model_.lengths().distal;
  const double max_strain = options_.closed_loop.max_correction_strain;
  Eigen::Vector3d out = correction;
  const double curvature = out.head<2>().norm();
  if (curvature > max_curvature) out.head<2>() *= max_curvature / curvature;
  out(2) = std::clamp(out(2), -max_strain, max_strain);
  return out;
}

Eigen::Vector3d ClosedLoopController::WithoutWindup(const Eigen::Vector3d& increment,
                                                    const Eigen::Vector3d& shortfall) const {
  // In tip millimetres, so that curvature and strain compare.
  const Eigen::Vector3d weights = TipWeights(model_);
  const Eigen::Vector3d missed = weights.cwiseProduct(shortfall);
  if (missed.norm() < kCarriedOut) return increment;
  const Eigen::Vector3d direction = missed.normalized();
  Eigen::Vector3d weighed = weights.cwiseProduct(increment);
  // A shortfall opposite to the increment means more of it cannot be had.
  const double toward_missed = weighed.dot(direction);
  if (toward_missed < 0.0) weighed -= toward_missed * direction;
  return weighed.cwiseQuotient(weights);
}

// The error that counts toward the integral: each part (the curvatures,
// eps1) only while the tip motion it stands for is beyond the deadband.
Eigen::Vector3d ClosedLoopController::OutsideDeadband(const Eigen::Vector3d& error) const {
  const Eigen::Vector3d motion = TipWeights(model_).cwiseProduct(error);
  const double deadband = options_.closed_loop.integral_deadband_mm;
  Eigen::Vector3d counted = error;
  if (motion.head<2>().norm() <= deadband) counted.head<2>().setZero();
  if (std::abs(motion(2)) <= deadband) counted(2) = 0.0;
  return counted;
}

Eigen::VectorXd ClosedLoopController::Propose(const ControlInput& input) {
  const ClosedLoopOptions& gains = options_.closed_loop;
  const bool fresh = Fresh(input, options_.watchdog);
  const Eigen::Vector3d error =
      fresh ? Eigen::Vector3d(Controlled(input.target - input.sensed.configuration))
            : Eigen::Vector3d::Zero();
  if (fresh && has_last_ && input.last_command.size() == model_.num_tendons()) {
    Eigen::Vector3d increment = input.dt * gains.integral * OutsideDeadband(error);
    if (gains.anti_windup) {
      increment =
          WithoutWindup(increment, Controlled(model_.Forward(input.last_command)) - last_desired_);
    }
    integral_ = Bounded(integral_ + increment);
  }
  Eigen::Vector3d proportional = gains.proportional * error;
  proportional(2) *= gains.strain_proportional;
  const Eigen::Vector3d correction = Bounded(proportional + integral_);
  const Configuration desired = WithControlled(input.target, Controlled(input.target) + correction);
  const InverseSolution inverse =
      model_.InverseWithMinimumTension(desired, options_.limits.min_tension);
  if (!inverse.feasible) return Stay(input);
  last_desired_ = Controlled(desired);
  has_last_ = true;
  return inverse.displacements;
}

ModelLessController::ModelLessController(const TendonModel& model, const ControllerOptions& options)
    : model_(model), options_(options) {
  CheckOptions(model, options);
  weight_ = TipWeights(model)(0);
  model_jacobian_ = weight_ * model.actuation().topRows<2>();
  jacobian_ = model_jacobian_;
}

Eigen::Vector2d ModelLessController::WeighedCurvature(const Configuration& q) const {
  return weight_ * q.head<2>();
}

const Eigen::VectorXd* ModelLessController::CommandAt(double time) const {
  const Eigen::VectorXd* found = nullptr;
  for (const auto& [sent, command] : history_) {
    if (sent > time) break;
    found = &command;
  }
  return found;
}

void ModelLessController::LearnFromSample(const SensedConfiguration& sensed) {
  const Eigen::VectorXd* command = CommandAt(sensed.time);
  if (command == nullptr) return;
  const Eigen::Vector2d sample = WeighedCurvature(sensed.configuration);
  if (last_sample_command_.size() == command->size()) {
    const Eigen::VectorXd dy = *command - last_sample_command_;
    const double dy_squared = dy.squaredNorm();
    const ModelLessOptions& opts = options_.model_less;
    if (dy_squared >= opts.min_update_step * opts.min_update_step) {
      const Eigen::Vector2d dq = sample - last_sample_;
      jacobian_ += opts.broyden_weight * (dq - jacobian_ * dy) * dy.transpose() / dy_squared;
      jacobian_ += opts.model_prior_weight * (model_jacobian_ - jacobian_);
      ++updates_;
    }
  }
  last_sample_ = sample;
  last_sample_command_ = *command;
  last_sample_time_ = sensed.time;
  // Commands older than the one in force at this sample are no longer needed.
  while (history_.size() > 1 && history_[1].first <= sensed.time) history_.pop_front();
}

Eigen::VectorXd ModelLessController::Propose(const ControlInput& input) {
  if (input.last_command.size() != jacobian_.cols()) return input.last_command;
  history_.emplace_back(input.time - input.dt, input.last_command);
  // Without samples to pair them with, keep no more than a lost sensing's worth.
  const double oldest = input.time - 2.0 * options_.watchdog.lost_age;
  while (history_.size() > 1 && history_[1].first < oldest) history_.pop_front();
  if (input.sensed.valid && input.sensed.time > last_sample_time_) LearnFromSample(input.sensed);
  if (!Fresh(input, options_.watchdog)) return Stay(input);

  return WithPretension(input, input.last_command + CurvatureStep(input));
}

Eigen::VectorXd ModelLessController::CurvatureStep(const ControlInput& input) const {
  const Eigen::Vector2d error = WeighedCurvature(input.target - input.sensed.configuration);
  const Eigen::Vector2d wanted = options_.model_less.gain * input.dt * error;
  const double damping = options_.model_less.damping;
  const Eigen::Matrix2d normal =
      jacobian_ * jacobian_.transpose() + damping * damping * Eigen::Matrix2d::Identity();
  return jacobian_.transpose() * normal.ldlt().solve(wanted);
}

Eigen::VectorXd ModelLessController::WithPretension(const ControlInput& input,
                                                    const Eigen::VectorXd& command) const {
  // Which of the redundant ways to pull carries out the curvatures that the
  // model sees in `command`: the model's least-norm choice with every
  // tendon taut, at an eps1 moved toward the sensed error.
  const double strain_error =
      input.target(kStrainDistal) - input.sensed.configuration(kStrainDistal);
  Configuration desired = model_.Forward(command);
  desired(kStrainDistal) += options_.model_less.gain * input.dt * strain_error;
  const InverseSolution inverse = model_.InverseWithMinimumTension(
      desired, options_.limits.min_tension + options_.model_less.pretension_margin);
  return inverse.feasible ? inverse.displacements : command;
}

std::unique_ptr<Controller> MakeController(const TendonModel& model,
                                           const ControllerOptions& options) {
  CheckOptions(model, options);
  switch (options.control_mode()) {
    case ControlMode::kOpenLoop:
      return std::make_unique<OpenLoopController>(model, options);
    case ControlMode::kClosedLoop:
      return std::make_unique<ClosedLoopController>(model, options);
    case ControlMode::kModelLess:
      return std::make_unique<ModelLessController>(model, options);
  }
  return nullptr;
}

}  // namespace shapesense
