#include "libs/control/tip_solver.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "libs/mechanics/configuration_geometry.h"

namespace shapesense {
namespace {

using Residual = std::function<Eigen::VectorXd(const Eigen::VectorXd&)>;

// Parameters are of order one: bend angles theta = kappa * L1 (rad) and
// eps1 * kStrainScale.
constexpr double kStrainScale = 100.0;

// `residuals`: the residual's size (known: evaluating it only for its size
// costs a minimum-tension solve on the shell).
Eigen::MatrixXd NumericJacobian(const Residual& residual, const Eigen::VectorXd& x,
                                Eigen::Index residuals) {
  constexpr double kStep = 1e-7;
  Eigen::MatrixXd jacobian(residuals, x.size());
  for (int j = 0; j < x.size(); ++j) {
    Eigen::VectorXd plus = x, minus = x;
    plus(j) += kStep;
    minus(j) -= kStep;
    jacobian.col(j) = (residual(plus) - residual(minus)) / (2.0 * kStep);
  }
  return jacobian;
}

// Levenberg-Marquardt: a handful of parameters, so dense and simple.
Eigen::VectorXd MinimizeSquares(const Residual& residual, Eigen::VectorXd x) {
  double lambda = 1e-3;
  Eigen::VectorXd r = residual(x);
  for (int iteration = 0; iteration < 200 && r.norm() > 1e-9; ++iteration) {
    const Eigen::MatrixXd jacobian = NumericJacobian(residual, x, r.size());
    const Eigen::MatrixXd normal = jacobian.transpose() * jacobian;
    const Eigen::VectorXd gradient = jacobian.transpose() * r;
    bool improved = false;
    for (int attempt = 0; attempt < 12 && !improved; ++attempt) {
      Eigen::MatrixXd damped = normal;
      damped.diagonal().array() += lambda * (normal.diagonal().array() + 1e-9);
      const Eigen::VectorXd trial = x - damped.ldlt().solve(gradient);
      const Eigen::VectorXd trial_r = residual(trial);
      if (trial_r.squaredNorm() < r.squaredNorm()) {
        x = trial;
        r = trial_r;
        lambda = std::max(lambda * 0.1, 1e-12);
        improved = true;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;
  }
  return x;
}

Configuration ConfigurationOf(const TendonModel& model, double theta_x, double theta_z,
                              double eps1) {
  const double distal = model.lengths().distal;
  return Configuration(theta_x / distal, theta_z / distal, model.ProximalPerDistalStrain() * eps1,
                       eps1);
}

// A first guess from the chord between the distal section's start and the
// tip: the arc turns by twice the chord's angle to the axis, and its length
// gives eps1, which moves the start through eps0; a few rounds settle it.
Eigen::Vector3d InitialGuess(const TendonModel& model, const Vec3& tip) {
  const SectionLengths rest = model.lengths();
  double eps1 = 0.0, theta = 0.0;
  const double phi = std::atan2(tip.z(), tip.x());
  for (int round = 0; round < 5; ++round) {
    const double start = rest.proximal * (1.0 - model.ProximalPerDistalStrain() * eps1);
    const Vec3 chord = tip - Vec3(0.0, start, 0.0);
    theta = 2.0 * std::atan2(std::hypot(chord.x(), chord.z()), std::max(chord.y(), 1e-9));
    const double arc =
        theta > 1e-9 ? chord.norm() * theta / (2.0 * std::sin(theta / 2.0)) : chord.norm();
    eps1 = std::clamp(1.0 - arc / rest.distal, 0.0, 0.2);
  }
  return {theta * std::sin(phi), -theta * std::cos(phi), eps1 * kStrainScale};
}

}  // namespace

double MinimumDistalStrain(const TendonModel& model, double kappa_x, double kappa_z,
                           double min_tension) {
  const InverseSolution least =
      model.InverseWithMinimumTension(Configuration(kappa_x, kappa_z, 0.0, 0.0), min_tension);
  return least.state.configuration(kStrainDistal);
}

TipSolution ConfigurationForTip(const TendonModel& model, const Vec3& tip, double min_tension) {
  const SectionLengths rest = model.lengths();
  const auto tip_error = [&](const Configuration& q) -> Eigen::VectorXd {
    return BaseFromTip(q, rest).translation() - tip;
  };
  // First with eps1 free, which needs no tension floor at every step.
  const Residual free_strain = [&](const Eigen::VectorXd& x) {
    return tip_error(ConfigurationOf(model, x(0), x(1), x(2) / kStrainScale));
  };
  const Eigen::VectorXd free = MinimizeSquares(free_strain, InitialGuess(model, tip));
  const Configuration q = ConfigurationOf(model, free(0), free(1), free(2) / kStrainScale);
  if (q(kStrainDistal) >= MinimumDistalStrain(model, q(kKappaX), q(kKappaZ), min_tension)) {
    return {q, tip_error(q).norm()};
  }
  // Too little compression for taut tendons: eps1 = its floor at the
  // curvature + (u / kStrainScale)^2, so that every parameter value is a
  // configuration the tendons can hold taut. Several starts of u, since the
  // map from (bend, compression) to the tip can fold.
  const auto on_shell = [&](const Eigen::VectorXd& x) {
    const double floor =
        MinimumDistalStrain(model, x(0) / rest.distal, x(1) / rest.distal, min_tension);
    const double above = x(2) / kStrainScale;
    return ConfigurationOf(model, x(0), x(1), floor + above * above);
  };
  const Residual shell_residual = [&](const Eigen::VectorXd& x) { return tip_error(on_shell(x)); };
  TipSolution best;
  best.residual = std::numeric_limits<double>::infinity();
  for (const double u : {0.0, 0.3, 1.0}) {
    const Eigen::VectorXd x = MinimizeSquares(shell_residual, Eigen::Vector3d(free(0), free(1), u));
    const Configuration candidate = on_shell(x);
    const double distance = tip_error(candidate).norm();
    if (distance < best.residual) best = {candidate, distance};
    if (best.residual < 1e-9) break;
  }
  return best;
}

}  // namespace shapesense
