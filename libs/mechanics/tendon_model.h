#pragma once

// The linear tendon-driven continuum manipulator model (after the reference;
// conventions in docs/mechanics.md):
//
//   configuration  q = [kappa_x, kappa_z, eps0, eps1]   (1/mm, 1/mm, -, -)
//   displacements  y, one per tendon, mm (positive = pulled)
//   tensions       tau = C_m^-1 y, N
//   forward        q = A y,  A = K_m^-1 D C_m^-1
//
// Equilibrium K_m q = D tau and compatibility y = D^T L0 q + L_t K_t^-1 tau
// hold for every solution.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "libs/mechanics/configuration.h"
#include "libs/mechanics/manipulator_options.h"

namespace shapesense {

StiffnessVector StiffnessFromOptions(const StiffnessOptions& options);
StiffnessOptions StiffnessToOptions(const StiffnessVector& stiffness);

// What the model predicts for one set of displacements.
struct TendonState {
  Configuration configuration = Configuration::Zero();
  Eigen::VectorXd tensions;  // N
  // Tendons whose tension is negative: the linear model has them push, which
  // a tendon cannot, so the configuration is not to be trusted.
  std::vector<int> slack_tendons;
  // Per tendon, how much longer the tendon is than its path, mm; non-zero only
  // from SolveWithSlack, where a slack tendon carries no tension.
  Eigen::VectorXd slack_lengths;

  bool has_slack() const { return !slack_tendons.empty(); }
};

struct InverseSolution {
  bool feasible = false;
  Eigen::VectorXd displacements;  // y, mm
  TendonState state;              // the model's forward prediction for y
};

class TendonModel {
 public:
  // Throws std::invalid_argument when options.Validate() fails.
  explicit TendonModel(const ManipulatorOptions& options);

  int num_tendons() const { return static_cast<int>(moment_arms_.cols()); }
  const ManipulatorOptions& options() const { return options_; }
  SectionLengths lengths() const { return {options_.proximal_length, options_.distal_length}; }
  const StiffnessVector& stiffness() const { return stiffness_; }
  // The same manipulator with other stiffnesses (estimation).
  TendonModel WithStiffness(const StiffnessVector& stiffness) const;

  const Eigen::Matrix4Xd& moment_arms() const { return moment_arms_; }             // D
  const Eigen::Vector4d& configuration_lengths() const { return lengths_; }        // diag(L0)
  const Eigen::VectorXd& tendon_compliance() const { return tendon_compliance_; }  // L_t/K_t
  const Eigen::MatrixXd& displacement_compliance() const { return compliance_; }   // C_m
  const Eigen::Matrix4Xd& actuation() const { return actuation_; }                 // A

  // eps0 / eps1 of every reachable configuration: both sections carry the
  // same total tendon force, so K_a0 eps0 = K_a1 eps1.
  double ProximalPerDistalStrain() const { return stiffness_(3) / stiffness_(2); }

  // q = A y.
  Configuration Forward(const Eigen::VectorXd& displacements) const;
  // tau = C_m^-1 y.
  Eigen::VectorXd Tensions(const Eigen::VectorXd& displacements) const;
  // The linear model with slack flagged (tendons with negative tension).
  TendonState Solve(const Eigen::VectorXd& displacements) const;
  // Goes past the linear model: slack tendons carry no tension and leave the
  // others to balance the section (a complementarity problem: tau >= 0,
  // slack >= 0, tau_i slack_i = 0). Equals Solve() when nothing is slack.
  TendonState SolveWithSlack(const Eigen::VectorXd& displacements) const;

  // Least-norm displacements for a desired configuration. eps0 is not free
  // (it follows eps1, see ProximalPerDistalStrain), so its row of A is pruned
  // and y = Ab^T (Ab Ab^T)^-1 [kappa_x, kappa_z, eps1] with Ab the other three
  // rows; the achieved eps0 is in the returned state. Tensions may come out
  // negative (flagged as slack).
  InverseSolution Inverse(const Configuration& desired) const;
  // As Inverse, but every tension stays >= min_tension (N): the curvatures are
  // met exactly, eps1 is at least the desired one (pretension compresses the
  // section), and among those y has the least norm. Equals Inverse() when its
  // tensions already meet the floor and raising eps1 would not shorten y.
  // Always feasible for a validated layout (the tendons surround the axis, so
  // a positive pretension exists that bends nothing); at most 19 tendons.
  InverseSolution InverseWithMinimumTension(const Configuration& desired, double min_tension) const;

 private:
  ManipulatorOptions options_;
  StiffnessVector stiffness_;
  Eigen::Matrix4Xd moment_arms_;
  Eigen::Vector4d lengths_;
  Eigen::VectorXd tendon_compliance_;
  Eigen::MatrixXd compliance_;
  Eigen::Matrix4Xd actuation_;
};

// Displacements that bend the distal section toward each tendon in turn by
// `bend_angle` (rad), every tendon held at >= min_tension: the articulations
// of the reference's frame registration. One entry per tendon.
std::vector<Eigen::VectorXd> TendonArticulations(const TendonModel& model, double bend_angle,
                                                 double min_tension);

// The curvatures [kappa_x, kappa_z] that bend the distal section by
// `bend_angle` over its rest length toward the direction phi in the base x-z
// plane (phi = atan2(z, x) of the direction the tip moves to).
Eigen::Vector2d CurvatureTowards(double phi, double bend_angle, double distal_length);

}  // namespace shapesense
