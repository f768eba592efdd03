#include "libs/control/controllers.h"

#include <gtest/gtest.h>

#include <random>

#include "libs/control/safety_gate.h"
#include "libs/control/targets.h"
#include "tests/libs/control/closed_loop_sim.h"
#include "tests/libs/mechanics/test_models.h"

namespace shapesense {
namespace {

ControlInput InputAt(double time, const Configuration& target, const Configuration& sensed,
                     const Eigen::VectorXd& last_command) {
  ControlInput input;
  input.time = time;
  input.dt = 0.01;
  input.target = target;
  input.sensed = {sensed, time - 0.05, true};
  input.last_command = last_command;
  return input;
}

std::vector<Configuration> SomeTargets(const TendonModel& model, int count, std::mt19937_64& rng) {
  const TargetResolver resolver(model, ControllerOptions{});
  std::uniform_real_distribution<double> phi(-3.2, 3.2), bend(0.2, 1.6);
  std::vector<Configuration> targets;
  for (int k = 0; k < count; ++k) {
    Target target;
    const double direction = phi(rng), angle = bend(rng);
    target.configuration.head<2>() = CurvatureTowards(direction, angle, model.lengths().distal);
    targets.push_back(resolver.Resolve(target).configuration);
  }
  return targets;
}

TEST(OpenLoopControllerTest, ProposesTheModelsInverseWithTautTendons) {
  const TendonModel model(testing::CatheterOptions());
  ControllerOptions options;
  options.mode = "open_loop";
  const std::unique_ptr<Controller> controller = MakeController(model, options);
  EXPECT_EQ(controller->mode(), ControlMode::kOpenLoop);
  std::mt19937_64 rng(31);
  for (const Configuration& target : SomeTargets(model, 50, rng)) {
    // Whatever is sensed: open loop does not look.
    const Eigen::VectorXd y = controller->Propose(
        InputAt(1.0, target, Configuration::Random(), Eigen::VectorXd::Zero(4)));
    EXPECT_EQ(y, model.InverseWithMinimumTension(target, options.limits.min_tension).displacements);
  }
}

// Against a plant equal to the model, no play, no noise: every mode lands on
// the targets exactly, and open loop needs no feedback to do it.
TEST(ControllersTest, EveryModeReachesTheTargetsOfAnExactPlant) {
  const TendonModel model(testing::CatheterOptions());
  std::mt19937_64 rng(32);
  const std::vector<Configuration> targets = SomeTargets(model, 5, rng);
  testing::LoopOptions loop;
  loop.curvature_noise = loop.strain_noise = 0.0;
  loop.hold_time = 10.0;
  for (const char* mode : {"open_loop", "closed_loop", "model_less"}) {
    ControllerOptions options;
    options.mode = mode;
    options.model_less.pretension_margin = 0.0;      // else eps1 stays a little high
    options.closed_loop.integral_deadband_mm = 0.0;  // else it stops within the deadband
    const testing::LoopResult result =
        testing::RunLoop(testing::CatheterOptions(), TendonPlantOptions{}, options, targets, loop);
    EXPECT_LT(testing::MaxOf(result.targets), 1e-4) << mode;
    EXPECT_EQ(result.violations.total(), 0) << mode;
  }
}

TEST(ClosedLoopControllerTest, AntiWindupKeepsTheIntegralFromRunningAway) {
  // The gate holds the tendons below what the target needs (a range too
  // short), so the error cannot close. Without anti-windup the integral runs
  // to its bound; with it, it settles where the gate's shortfall balances it.
  const TendonModel model(testing::CatheterOptions());
  Target asked;
  asked.configuration.head<2>() = CurvatureTowards(0.0, 1.5, model.lengths().distal);
  const Configuration target =
      TargetResolver(model, ControllerOptions{}).Resolve(asked).configuration;
  double integral[2] = {0.0, 0.0};
  for (const int with_anti_windup : {0, 1}) {
    ControllerOptions options;
    options.limits.range.max = 3.0;  // the target needs ~4.2 mm on tendon 0
    options.closed_loop.anti_windup = with_anti_windup == 1;
    const TendonModel plant_model(testing::CatheterOptions());
    SafetyGate gate(model, options.limits, options.watchdog,
                    SafetyEnvelope(model, options.limits).RestingCommand());
    ClosedLoopController controller(model, options);
    double time = 0.0;
    for (int step = 0; step < 2000; ++step) {
      time += 0.01;
      const Configuration sensed = plant_model.Forward(gate.command());
      const ControlInput input = InputAt(time, target, sensed, gate.command());
      gate.Apply(controller.Propose(input), 0.01, 0.05, false);
    }
    integral[with_anti_windup] = controller.integral().head<2>().norm() * model.lengths().distal;
  }
  const double bound = ControllerOptions{}.closed_loop.max_correction_bend;
  EXPECT_NEAR(integral[0], bound, 1e-9) << "without anti-windup: at the bound";
  EXPECT_LT(integral[1], 0.25 * bound) << "with anti-windup";
}

TEST(ClosedLoopControllerTest, StaleSensingFreezesTheIntegral) {
  const TendonModel model(testing::CatheterOptions());
  ClosedLoopController controller(model, ControllerOptions{});
  const Configuration target(0.004, 0.0, 0.0, 0.003);
  const Eigen::VectorXd y = model.InverseWithMinimumTension(target, 0.3).displacements;
  controller.Propose(InputAt(1.0, target, Configuration::Zero(), y));
  controller.Propose(InputAt(1.01, target, Configuration::Zero(), y));
  const Eigen::Vector3d frozen = controller.integral();
  EXPECT_GT(frozen.norm(), 0.0);
  ControlInput stale = InputAt(2.0, target, Configuration::Zero(), y);
  stale.sensed.time = 1.5;  // 0.5 s old
  controller.Propose(stale);
  EXPECT_EQ(controller.integral(), frozen);
}

TEST(ModelLessControllerTest, BroydenLearnsThePlantsJacobian) {
  // A plant 20% off the model, exact sensing: after moving through a few
  // targets, the estimate is closer to the plant's Jacobian than the model's.
  const TendonModel model(testing::CatheterOptions());
  TendonPlantOptions plant_options;
  plant_options.stiffness_factor = {1.2, 0.8, 1.0, 1.0, 0.8};
  TendonPlant plant(testing::CatheterOptions(), plant_options,
                    SafetyEnvelope(model, SafetyLimits{}).RestingCommand());
  ControllerOptions options;
  options.mode = "model_less";
  options.model_less.model_prior_weight = 0.0;
  ModelLessController controller(model, options);
  SafetyGate gate(model, options.limits, options.watchdog, plant.commanded());
  std::mt19937_64 rng(33);
  double time = 0.0;
  for (const Configuration& target : SomeTargets(model, 8, rng)) {
    for (int step = 0; step < 400; ++step) {
      time += 0.01;
      ControlInput input = InputAt(time, target, plant.configuration(), gate.command());
      input.sensed.time = time - 0.01;  // the plant as the last command left it
      plant.Command(gate.Apply(controller.Propose(input), 0.01, 0.01, false).command);
    }
  }
  const double weight = model.lengths().distal * model.lengths().distal / 2.0;
  // Dynamic sizes: GCC 12 warns of a null dereference in Eigen's 2 x n reductions.
  const Eigen::MatrixXd truth = weight * plant.true_model().actuation().topRows<2>();
  const Eigen::MatrixXd learned_error = Eigen::MatrixXd(controller.jacobian()) - truth;
  const Eigen::MatrixXd prior_error = Eigen::MatrixXd(controller.model_jacobian()) - truth;
  const double learned = learned_error.norm(), prior = prior_error.norm();
  EXPECT_GT(controller.updates(), 100);
  EXPECT_LT(learned, 0.5 * prior) << "learned " << learned << ", model " << prior;
}

TEST(ModelLessControllerTest, HoldsStillWithoutFreshSensing) {
  const TendonModel model(testing::CatheterOptions());
  ModelLessController controller(model, ControllerOptions{});
  const Eigen::VectorXd y = Eigen::Vector4d(1.0, 1.2, 0.8, 1.1);
  ControlInput input = InputAt(3.0, Configuration(0.005, 0, 0, 0.003), Configuration::Zero(), y);
  input.sensed.valid = false;
  EXPECT_EQ(controller.Propose(input), y);
  input.sensed.valid = true;
  input.sensed.time = 2.0;
  EXPECT_EQ(controller.Propose(input), y);
}

TEST(ControllersTest, MakeControllerChecksItsOptions) {
  const TendonModel model(testing::CatheterOptions());
  ControllerOptions options;
  options.mode = "model_less";
  EXPECT_EQ(MakeController(model, options)->mode(), ControlMode::kModelLess);
  options.mode = "closed_loop";
  EXPECT_EQ(MakeController(model, options)->mode(), ControlMode::kClosedLoop);
  options.limits.tendon_ranges = {{0, 1}};
  EXPECT_THROW(MakeController(model, options), std::invalid_argument);
  options.limits.tendon_ranges.clear();
  options.mode = "pid";
  EXPECT_THROW(MakeController(model, options), std::invalid_argument);
}

}  // namespace
}  // namespace shapesense
