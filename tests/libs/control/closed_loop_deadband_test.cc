// The closed loop's integral deadband (ClosedLoopOptions::integral_deadband_mm):
// each part of the integral, the curvatures' and eps1's, holds while its
// error, as tip motion (|kappa error| L1^2 / 2, |eps1 error| L1), is within
// the deadband, and integrates beyond it. And the proportional gain on eps1
// (strain_proportional).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "libs/control/controllers.h"
#include "tests/libs/mechanics/test_models.h"

namespace shapesense {
namespace {

using ::testing::HasSubstr;

constexpr double kDt = 0.01;
constexpr int kSteps = 50;

// A bend the model reaches with every tension 2 N above the floor, so that
// errors of either sign in eps1 can be carried out (below the floor's eps1,
// anti-windup would rightly hold the integral).
Configuration Target(const TendonModel& model) {
  const Configuration bend(0.004, 0.0, 0.0, 0.0);
  return model.Forward(model.InverseWithMinimumTension(bend, 2.3).displacements);
}

// The error in (kappa_x, kappa_z, eps1) whose tip motion is `tip_mm` along
// the unit `direction` of (bend x, bend z, stretch) in tip millimetres.
Eigen::Vector3d ErrorOfTipMotion(const TendonModel& model, const Eigen::Vector3d& direction,
                                 double tip_mm) {
  const double distal = model.lengths().distal;
  const Eigen::Vector3d per_unit(distal * distal / 2.0, distal * distal / 2.0, distal);
  return (tip_mm * direction.normalized()).cwiseQuotient(per_unit);
}

// The target with `error` (kappa_x, kappa_z, eps1) taken off: what is sensed.
Configuration SensedWithError(const Configuration& target, const Eigen::Vector3d& error) {
  Configuration sensed = target;
  sensed(kKappaX) -= error(0);
  sensed(kKappaZ) -= error(1);
  sensed(kStrainDistal) -= error(2);
  return sensed;
}

// Runs the controller kSteps times with the sensing fresh and a constant
// sensed error; the last command is the previous proposal (a gate that let
// everything through), so anti-windup takes nothing away. The integral after.
Eigen::Vector3d IntegralAfterSteps(const TendonModel& model, const ControllerOptions& options,
                                   const Eigen::Vector3d& error) {
  ClosedLoopController controller(model, options);
  const Configuration target = Target(model);
  const Configuration sensed = SensedWithError(target, error);
  Eigen::VectorXd last = model.InverseWithMinimumTension(target, 0.3).displacements;
  double time = 1.0;
  for (int step = 0; step < kSteps; ++step) {
    ControlInput input;
    input.time = time;
    input.dt = kDt;
    input.target = target;
    input.sensed = {sensed, time - 0.05, true};
    input.last_command = last;
    last = controller.Propose(input);
    time += kDt;
  }
  return controller.integral();
}

std::vector<Eigen::Vector3d> SomeDirections(int count) {
  std::mt19937_64 rng(51);
  std::normal_distribution<double> normal;
  std::vector<Eigen::Vector3d> directions = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                             Eigen::Vector3d::UnitZ()};
  while (static_cast<int>(directions.size()) < count) {
    directions.emplace_back(normal(rng), normal(rng), normal(rng));
  }
  return directions;
}

// Bending directions in the (bend x, bend z) plane, unit, the strain 0.
std::vector<Eigen::Vector3d> BendDirections(int count) {
  std::vector<Eigen::Vector3d> directions;
  for (int i = 0; i < count; ++i) {
    const double angle = 2.0 * std::acos(-1.0) * i / count + 0.3;
    directions.emplace_back(std::cos(angle), std::sin(angle), 0.0);
  }
  return directions;
}

// Every step but the first (which has no previous one) adds dt * gain * error;
// the errors are far below the correction bounds.
Eigen::Vector3d Integrated(const ControllerOptions& options, const Eigen::Vector3d& error) {
  return (kSteps - 1) * kDt * options.closed_loop.integral * error;
}

TEST(ClosedLoopDeadbandTest, TheCurvaturesIntegralHoldsWhileTheirErrorIsWithinTheDeadband) {
  const TendonModel model(testing::CatheterOptions());
  const ControllerOptions options;
  const double deadband = options.closed_loop.integral_deadband_mm;
  ASSERT_GT(deadband, 0.0);
  // In every bending direction: a sum or a max of the components instead of
  // the norm would integrate some of these.
  for (const Eigen::Vector3d& direction : BendDirections(16)) {
    for (const double fraction : {0.1, 0.5, 0.99}) {
      const Eigen::Vector3d error = ErrorOfTipMotion(model, direction, fraction * deadband);
      EXPECT_EQ(IntegralAfterSteps(model, options, error), Eigen::Vector3d::Zero())
          << "direction " << direction.transpose() << ", " << fraction << " of the deadband";
    }
  }
}

TEST(ClosedLoopDeadbandTest, TheCurvaturesIntegralGrowsJustBeyondTheDeadband) {
  const TendonModel model(testing::CatheterOptions());
  const ControllerOptions options;
  const double deadband = options.closed_loop.integral_deadband_mm;
  for (const Eigen::Vector3d& direction : BendDirections(16)) {
    const Eigen::Vector3d error = ErrorOfTipMotion(model, direction, 1.01 * deadband);
    const Eigen::Vector3d integral = IntegralAfterSteps(model, options, error);
    const Eigen::Vector3d expected = Integrated(options, error);
    EXPECT_LT((integral - expected).norm(), 1e-6 * expected.norm())
        << "direction " << direction.transpose() << ": " << integral.transpose() << " vs "
        << expected.transpose();
  }
}

TEST(ClosedLoopDeadbandTest, EachPartHasItsOwnDeadband) {
  const TendonModel model(testing::CatheterOptions());
  const ControllerOptions options;
  const double deadband = options.closed_loop.integral_deadband_mm;
  const Eigen::Vector2d bend_within =
      ErrorOfTipMotion(model, Eigen::Vector3d(1, 1, 0), 0.9 * deadband).head<2>();
  const Eigen::Vector2d bend_beyond =
      ErrorOfTipMotion(model, Eigen::Vector3d(1, 1, 0), 1.1 * deadband).head<2>();
  const double strain_within = ErrorOfTipMotion(model, Eigen::Vector3d::UnitZ(), 0.9 * deadband)(2);
  const double strain_beyond = ErrorOfTipMotion(model, Eigen::Vector3d::UnitZ(), 1.1 * deadband)(2);
  // Together both are beyond the deadband (their norm is); each on its own is not.
  Eigen::Vector3d error(bend_within(0), bend_within(1), strain_within);
  EXPECT_EQ(IntegralAfterSteps(model, options, error), Eigen::Vector3d::Zero());
  error << bend_beyond, strain_within;
  Eigen::Vector3d integral = IntegralAfterSteps(model, options, error);
  EXPECT_LT((integral.head<2>() - Integrated(options, error).head<2>()).norm(),
            1e-6 * error.head<2>().norm());
  EXPECT_EQ(integral(2), 0.0);
  error << bend_within, strain_beyond;
  integral = IntegralAfterSteps(model, options, error);
  EXPECT_EQ(integral.head<2>(), Eigen::Vector2d::Zero());
  EXPECT_NEAR(integral(2), Integrated(options, error)(2), 1e-6 * std::abs(error(2)));
}

// The proportional term alone (integral 0): the correction the controller
// asks for, read back through the model from its proposal.
Eigen::Vector3d ProportionalCorrection(const TendonModel& model, const ControllerOptions& options,
                                       const Eigen::Vector3d& error) {
  ClosedLoopController controller(model, options);
  const Configuration target = Target(model);
  const Configuration sensed = SensedWithError(target, error);
  ControlInput input;
  input.time = 1.0;
  input.dt = kDt;
  input.target = target;
  input.sensed = {sensed, 0.95, true};
  const Configuration reached = model.Forward(controller.Propose(input));
  return {reached(kKappaX) - target(kKappaX), reached(kKappaZ) - target(kKappaZ),
          reached(kStrainDistal) - target(kStrainDistal)};
}

TEST(ClosedLoopDeadbandTest, TheStrainsProportionalGainIsAFractionOfTheBends) {
  const TendonModel model(testing::CatheterOptions());
  ControllerOptions options;
  options.closed_loop.integral = 0.0;
  const Eigen::Vector3d error(2e-4, -1e-4, 1e-3);
  for (const double fraction : {0.0, 0.1, 1.0}) {
    options.closed_loop.strain_proportional = fraction;
    const Eigen::Vector3d correction = ProportionalCorrection(model, options, error);
    const double gain = options.closed_loop.proportional;
    EXPECT_NEAR(correction(0), gain * error(0), 1e-9) << fraction;
    EXPECT_NEAR(correction(1), gain * error(1), 1e-9) << fraction;
    EXPECT_NEAR(correction(2), fraction * gain * error(2), 1e-9) << fraction;
  }
  options.closed_loop.strain_proportional = 1.5;
  EXPECT_THAT(options.closed_loop.Validate(), HasSubstr("strain_proportional"));
}

TEST(ClosedLoopDeadbandTest, ZeroDeadbandIntegratesAnyNonzeroError) {
  const TendonModel model(testing::CatheterOptions());
  ControllerOptions options;
  options.closed_loop.integral_deadband_mm = 0.0;
  for (const Eigen::Vector3d& direction : SomeDirections(6)) {
    for (const double tip_mm : {1e-6, 1e-3, 0.1}) {
      const Eigen::Vector3d error = ErrorOfTipMotion(model, direction, tip_mm);
      const Eigen::Vector3d integral = IntegralAfterSteps(model, options, error);
      EXPECT_GT(integral.norm(), 0.0) << direction.transpose() << ", " << tip_mm << " mm";
      EXPECT_GT(integral.dot(error), 0.0) << "toward the error";
    }
  }
}

TEST(ClosedLoopDeadbandTest, ValidateRejectsANegativeDeadband) {
  ClosedLoopOptions closed_loop;
  EXPECT_EQ(closed_loop.Validate(), "");
  closed_loop.integral_deadband_mm = 0.0;
  EXPECT_EQ(closed_loop.Validate(), "");
  closed_loop.integral_deadband_mm = -0.1;
  EXPECT_THAT(closed_loop.Validate(), HasSubstr("integral_deadband_mm"));

  ControllerOptions options;
  options.closed_loop = closed_loop;
  EXPECT_THAT(options.Validate(), HasSubstr("integral_deadband_mm"));
  const TendonModel model(testing::CatheterOptions());
  EXPECT_THROW(ClosedLoopController(model, options), std::invalid_argument);
}

}  // namespace
}  // namespace shapesense
