// The closed loop's integral deadband (ClosedLoopOptions::integral_deadband_mm):
// the integral holds while the sensed error, as tip motion (curvature errors
// times L1^2 / 2, the strain error times L1, their Euclidean norm), is within
// the deadband, and integrates beyond it.
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

// Runs the controller kSteps times with the sensing fresh and a constant
// sensed error; the last command is the previous proposal (a gate that let
// everything through), so anti-windup takes nothing away. The integral after.
Eigen::Vector3d IntegralAfterSteps(const TendonModel& model, const ControllerOptions& options,
                                   const Eigen::Vector3d& error) {
  ClosedLoopController controller(model, options);
  const Configuration target = Target(model);
  Configuration sensed = target;
  sensed(kKappaX) -= error(0);
  sensed(kKappaZ) -= error(1);
  sensed(kStrainDistal) -= error(2);
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

TEST(ClosedLoopDeadbandTest, TheIntegralHoldsWhileTheErrorIsWithinTheDeadband) {
  const TendonModel model(testing::CatheterOptions());
  const ControllerOptions options;
  const double deadband = options.closed_loop.integral_deadband_mm;
  ASSERT_GT(deadband, 0.0);
  // Along mixed directions too: a sum or a max of the components instead of
  // the norm would integrate some of these.
  for (const Eigen::Vector3d& direction : SomeDirections(20)) {
    for (const double fraction : {0.1, 0.5, 0.99}) {
      const Eigen::Vector3d error = ErrorOfTipMotion(model, direction, fraction * deadband);
      EXPECT_EQ(IntegralAfterSteps(model, options, error), Eigen::Vector3d::Zero())
          << "direction " << direction.transpose() << ", " << fraction << " of the deadband";
    }
  }
}

TEST(ClosedLoopDeadbandTest, TheIntegralGrowsJustBeyondTheDeadband) {
  const TendonModel model(testing::CatheterOptions());
  const ControllerOptions options;
  const double deadband = options.closed_loop.integral_deadband_mm;
  for (const Eigen::Vector3d& direction : SomeDirections(20)) {
    const Eigen::Vector3d error = ErrorOfTipMotion(model, direction, 1.01 * deadband);
    const Eigen::Vector3d integral = IntegralAfterSteps(model, options, error);
    // Every step but the first (which has no previous one) adds dt * gain * error;
    // the error is far below the correction bounds.
    const Eigen::Vector3d expected = (kSteps - 1) * kDt * options.closed_loop.integral * error;
    EXPECT_LT((integral - expected).norm(), 1e-6 * expected.norm())
        << "direction " << direction.transpose() << ": " << integral.transpose() << " vs "
        << expected.transpose();
  }
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
