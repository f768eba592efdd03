#include "libs/mechanics/tendon_model.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <stdexcept>

#include "libs/mechanics/constrained_solvers.h"
#include "libs/mechanics/tendon_matrices.h"

namespace shapesense {
namespace {

Eigen::Matrix4Xd MomentArmsOf(const std::vector<TendonOptions>& tendons) {
  Eigen::Matrix4Xd arms(4, static_cast<int>(tendons.size()));
  for (size_t i = 0; i < tendons.size(); ++i) {
    arms.col(static_cast<int>(i)) << tendons[i].dz, -tendons[i].dx, 1.0, 1.0;
  }
  return arms;
}

Eigen::VectorXd TendonComplianceOf(const std::vector<TendonOptions>& tendons) {
  Eigen::VectorXd compliance(static_cast<int>(tendons.size()));
  for (size_t i = 0; i < tendons.size(); ++i) {
    compliance(static_cast<int>(i)) = tendons[i].length / tendons[i].stiffness;
  }
  return compliance;
}

std::vector<int> NegativeEntries(const Eigen::VectorXd& values) {
  std::vector<int> out;
  for (int i = 0; i < values.size(); ++i) {
    if (values(i) < 0.0) out.push_back(i);
  }
  return out;
}

// Rows kappa_x, kappa_z and eps1 of A: the independent ones.
Eigen::Matrix3Xd PrunedActuation(const Eigen::Matrix4Xd& actuation) {
  Eigen::Matrix3Xd pruned(3, actuation.cols());
  pruned << actuation.row(kKappaX), actuation.row(kKappaZ), actuation.row(kStrainDistal);
  return pruned;
}

}  // namespace

StiffnessVector StiffnessFromOptions(const StiffnessOptions& options) {
  return {options.bend_x, options.bend_z, options.axial_proximal, options.axial_distal};
}

StiffnessOptions StiffnessToOptions(const StiffnessVector& stiffness) {
  return {stiffness(0), stiffness(1), stiffness(2), stiffness(3)};
}

TendonModel::TendonModel(const ManipulatorOptions& options) : options_(options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw std::invalid_argument("manipulator model: " + error);
  }
  stiffness_ = StiffnessFromOptions(options.stiffness);
  moment_arms_ = MomentArmsOf(options.tendons);
  lengths_ << options.distal_length, options.distal_length, options.proximal_length,
      options.distal_length;
  tendon_compliance_ = TendonComplianceOf(options.tendons);
  compliance_ = DisplacementCompliance(moment_arms_, lengths_, stiffness_, tendon_compliance_);
  actuation_ = ActuationMatrix(moment_arms_, lengths_, stiffness_, tendon_compliance_);
}

TendonModel TendonModel::WithStiffness(const StiffnessVector& stiffness) const {
  ManipulatorOptions options = options_;
  options.stiffness = StiffnessToOptions(stiffness);
  return TendonModel(options);
}

Configuration TendonModel::Forward(const Eigen::VectorXd& displacements) const {
  return actuation_ * displacements;
}

Eigen::VectorXd TendonModel::Tensions(const Eigen::VectorXd& displacements) const {
  return compliance_.ldlt().solve(displacements);
}

TendonState TendonModel::Solve(const Eigen::VectorXd& displacements) const {
  TendonState state;
  state.tensions = Tensions(displacements);
  state.configuration = (moment_arms_ * state.tensions).cwiseQuotient(stiffness_);
  state.slack_tendons = NegativeEntries(state.tensions);
  state.slack_lengths = Eigen::VectorXd::Zero(num_tendons());
  return state;
}

TendonState TendonModel::SolveWithSlack(const Eigen::VectorXd& displacements) const {
  // The tensions solve: tau >= 0, w = C_m tau - y >= 0, tau_i w_i = 0, where
  // w_i is the length by which tendon i is longer than its path.
  const std::optional<Eigen::VectorXd> tensions = SolveComplementarity(compliance_, displacements);
  if (!tensions) throw std::logic_error("SolveWithSlack: pivoting did not converge");
  TendonState state;
  state.tensions = *tensions;
  state.configuration = (moment_arms_ * state.tensions).cwiseQuotient(stiffness_);
  state.slack_lengths = (compliance_ * state.tensions - displacements).cwiseMax(0.0);
  for (int i = 0; i < num_tendons(); ++i) {
    if (state.tensions(i) <= 0.0 && state.slack_lengths(i) > 0.0) state.slack_tendons.push_back(i);
  }
  return state;
}

InverseSolution TendonModel::Inverse(const Configuration& desired) const {
  const Eigen::Matrix3Xd pruned = PrunedActuation(actuation_);
  const Eigen::Vector3d target(desired(kKappaX), desired(kKappaZ), desired(kStrainDistal));
  InverseSolution solution;
  solution.feasible = true;
  solution.displacements = pruned.transpose() * (pruned * pruned.transpose()).ldlt().solve(target);
  solution.state = Solve(solution.displacements);
  return solution;
}

InverseSolution TendonModel::InverseWithMinimumTension(const Configuration& desired,
                                                       double min_tension) const {
  // min |y|^2  s.t.  curvature rows of A y = desired curvatures,
  //                  eps1 row of A y >= desired eps1,  C_m^-1 y >= min_tension.
  const int n = num_tendons();
  const Eigen::MatrixXd tension_rows = compliance_.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
  Eigen::MatrixXd inequality(n + 1, n);
  inequality << actuation_.row(kStrainDistal), tension_rows;
  Eigen::VectorXd inequality_rhs(n + 1);
  inequality_rhs << desired(kStrainDistal), Eigen::VectorXd::Constant(n, min_tension);
  const std::optional<Eigen::VectorXd> y =
      LeastNormWithInequalities(actuation_.topRows(2), desired.head(2), inequality, inequality_rhs);
  InverseSolution solution;
  solution.feasible = y.has_value();
  if (!y) return solution;
  solution.displacements = *y;
  solution.state = Solve(*y);
  return solution;
}

Eigen::Vector2d CurvatureTowards(double phi, double bend_angle, double distal_length) {
  const double curvature = bend_angle / distal_length;
  return {curvature * std::sin(phi), -curvature * std::cos(phi)};
}

std::vector<Eigen::VectorXd> TendonArticulations(const TendonModel& model, double bend_angle,
                                                 double min_tension) {
  std::vector<Eigen::VectorXd> out;
  for (const TendonOptions& tendon : model.options().tendons) {
    Configuration desired = Configuration::Zero();
    desired.head<2>() =
        CurvatureTowards(std::atan2(tendon.dz, tendon.dx), bend_angle, model.lengths().distal);
    out.push_back(model.InverseWithMinimumTension(desired, min_tension).displacements);
  }
  return out;
}

}  // namespace shapesense
