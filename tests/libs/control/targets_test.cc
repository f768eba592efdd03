#include "libs/control/targets.h"

#include <gtest/gtest.h>

#include <random>

#include "libs/control/tip_solver.h"
#include "libs/core/error.h"
#include "libs/mechanics/configuration_geometry.h"
#include "tests/libs/mechanics/test_models.h"

namespace shapesense {
namespace {

void ExpectParseError(bool csv, const std::string& text, const std::string& fragment) {
  try {
    if (csv) {
      ParseTrajectoryCsv(text, "t.csv");
    } else {
      ParseTrajectoryYaml(text, "t.yaml");
    }
    ADD_FAILURE() << "accepted: " << text;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos)
        << e.what() << "\n  expected: " << fragment;
  }
}

TEST(TrajectoryParseTest, YamlHoldsConfigurationsAndTips) {
  const Trajectory t = ParseTrajectoryYaml(
      "interpolation: step\n"
      "targets:\n"
      "  - {time: 0, q: [0.003, -0.001, 0, 0.004]}\n"
      "  - time: 2.5\n"
      "    tip: [20, 755, -8]\n",
      "t.yaml");
  EXPECT_FALSE(t.interpolate);
  ASSERT_EQ(t.targets.size(), 2u);
  EXPECT_EQ(t.targets[0].kind, TargetKind::kConfiguration);
  EXPECT_EQ(t.targets[0].configuration, Configuration(0.003, -0.001, 0.0, 0.004));
  EXPECT_EQ(t.targets[1].kind, TargetKind::kTipPosition);
  EXPECT_EQ(t.targets[1].time, 2.5);
  EXPECT_EQ(t.targets[1].tip, Vec3(20.0, 755.0, -8.0));
  EXPECT_TRUE(ParseTrajectoryYaml("targets: [{time: 1, q: [0, 0, 0, 0]}]", "t").interpolate);
}

TEST(TrajectoryParseTest, YamlRejectsMalformedTargetsWithAReason) {
  const std::string head = "targets:\n  - {time: 0, q: [0, 0, 0, 0]}\n";
  ExpectParseError(false, "targets: [{time: 0, q: [0, .nan, 0, 0]}]",
                   "t.yaml: targets[0].q[1]: expected a finite number");
  ExpectParseError(false, "targets: [{time: 0, q: [0, 0, 0]}]",
                   "targets[0].q: expected a sequence of 4 numbers");
  ExpectParseError(false, "targets: [{time: 0, tip: [0, 0, x]}]",
                   "targets[0].tip[2]: expected a number");
  ExpectParseError(false, "targets: [{time: 0, q: [0, 0, 0, 0], tip: [0, 0, 0]}]",
                   "targets[0]: expected exactly one of q");
  ExpectParseError(false, "targets: [{q: [0, 0, 0, 0]}]", "targets[0].time: missing");
  ExpectParseError(false, head + "  - {time: 0, q: [0, 0, 0, 0]}\n",
                   "targets[1].time: expected times increasing, got 0 s after 0 s");
  ExpectParseError(false, "targets: [{time: -1, q: [0, 0, 0, 0]}]", "expected a time >= 0");
  ExpectParseError(false, "targets: [{time: 0, q: [0, 0, 0, 0], speed: 2}]",
                   "targets[0].speed: unknown key");
  ExpectParseError(false, head + "loop: true\n", "t.yaml: loop: unknown key");
  ExpectParseError(false, head + "interpolation: cubic\n",
                   "interpolation: expected linear or step");
  ExpectParseError(false, "targets: []", "expected at least one target");
  ExpectParseError(false, "- 1\n- 2\n", "expected a map with targets");
  ExpectParseError(false, "targets: [{time: 0", "not valid YAML");
}

TEST(TrajectoryParseTest, CsvHoldsEitherKindInAnyColumnOrder) {
  const Trajectory q = ParseTrajectoryCsv(
      "# a comment\n"
      "kappa_x, time, kappa_z, eps1, eps0\n"
      "\n"
      "0.002, 0.0, -0.001, 0.004, 0.001\n"
      "0.003, 1.5, 0, 0.005, 0\n",
      "t.csv");
  ASSERT_EQ(q.targets.size(), 2u);
  EXPECT_EQ(q.targets[0].configuration, Configuration(0.002, -0.001, 0.001, 0.004));
  EXPECT_EQ(q.targets[1].time, 1.5);
  const Trajectory tip = ParseTrajectoryCsv("time,tip_x,tip_y,tip_z\n0,1,750,2\n", "t.csv");
  ASSERT_EQ(tip.targets.size(), 1u);
  EXPECT_EQ(tip.targets[0].kind, TargetKind::kTipPosition);
  EXPECT_EQ(tip.targets[0].tip, Vec3(1.0, 750.0, 2.0));
}

TEST(TrajectoryParseTest, CsvRejectsMalformedLinesWithAReason) {
  const std::string header = "time,kappa_x,kappa_z,eps0,eps1\n";
  ExpectParseError(true, header + "0,0,0,0\n", "t.csv: line 2: expected 5 columns, got 4");
  ExpectParseError(true, header + "0,0,0,0,0,0\n", "line 2: expected 5 columns, got 6");
  ExpectParseError(true, header + "0,0,abc,0,0\n", "line 2, kappa_z: expected a number, got 'abc'");
  ExpectParseError(true, header + "0,0,nan,0,0\n", "line 2, kappa_z: expected a finite number");
  ExpectParseError(true, header + "0,0,,0,0\n", "line 2, kappa_z: expected a number, got ''");
  ExpectParseError(true, header + "1,0,0,0,0\n# note\n0.5,0,0,0,0\n",
                   "line 4, time: expected times increasing, got 0.5 s after 1 s");
  ExpectParseError(true, "time,kappa_x,kappa_z\n0,0,0\n", "line 1: expected a header");
  ExpectParseError(true, "time,tip_x,tip_y,tip_z,extra\n", "line 1: expected a header");
  ExpectParseError(true, "# nothing\n", "expected a header and at least one target");
  ExpectParseError(true, header, "expected at least one target");
}

class TargetResolverTest : public ::testing::Test {
 protected:
  TendonModel model_{testing::CatheterOptions()};
  ControllerOptions options_;
  std::mt19937_64 rng_{21};

  // Curvature within the bound, toward any direction; eps1 random and small.
  Configuration RandomAsked() {
    std::uniform_real_distribution<double> phi(-3.2, 3.2), bend(0.0, 1.9), strain(0.0, 0.01);
    Configuration q = Configuration::Zero();
    q.head<2>() = CurvatureTowards(phi(rng_), bend(rng_), model_.lengths().distal);
    q(kStrainDistal) = strain(rng_);
    return q;
  }
};

TEST_F(TargetResolverTest, ReachableConfigurationsKeepTheirCurvatureAndTautTendons) {
  const TargetResolver resolver(model_, options_);
  for (int trial = 0; trial < 300; ++trial) {
    Target target;
    target.configuration = RandomAsked();
    const ResolvedTarget r = resolver.Resolve(target);
    ASSERT_TRUE(r.ok) << r.reason;
    const Configuration& q = r.configuration;
    EXPECT_LT((q - target.configuration).head<2>().norm(), 1e-12);
    EXPECT_GE(q(kStrainDistal), target.configuration(kStrainDistal) - 1e-12);
    EXPECT_NEAR(q(kStrainProximal), model_.ProximalPerDistalStrain() * q(kStrainDistal), 1e-12);
    EXPECT_GE(model_.Tensions(r.displacements).minCoeff(), options_.limits.min_tension - 1e-9);
    EXPECT_LT((model_.Forward(r.displacements) - q).norm(), 1e-12);
  }
}

TEST_F(TargetResolverTest, OutOfRangeTargetsAreRejectedWithAReason) {
  const TargetResolver resolver(model_, options_);
  const auto reason = [&](const Configuration& q) {
    Target target;
    target.configuration = q;
    const ResolvedTarget r = resolver.Resolve(target);
    EXPECT_FALSE(r.ok);
    return r.reason;
  };
  const double bound = resolver.curvature_bound();
  EXPECT_NE(reason(Configuration(bound * 1.01, 0, 0, 0)).find("beyond the bound"),
            std::string::npos);
  EXPECT_NE(reason(Configuration(0, 0, 0, -0.001)).find("eps1 -0.001: expected a compression"),
            std::string::npos);
  EXPECT_NE(reason(Configuration(0, 0, 0, 0.06)).find("workspace.max_distal_strain"),
            std::string::npos);
  EXPECT_NE(reason(Configuration(0, std::nan(""), 0, 0)).find("q: expected finite numbers"),
            std::string::npos);
  // A tendon range too short for a large bend.
  ControllerOptions tight = options_;
  tight.limits.range.max = 3.0;
  const TargetResolver short_range(model_, tight);
  Target big;
  big.configuration.head<2>() = CurvatureTowards(0.0, 1.8, model_.lengths().distal);
  const ResolvedTarget r = short_range.Resolve(big);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.reason.find("needs tendon 0 at"), std::string::npos) << r.reason;
  EXPECT_NE(r.reason.find("outside its range [-1, 3] mm"), std::string::npos) << r.reason;
}

TEST_F(TargetResolverTest, TipTargetsRoundTripThroughTheTipSolver) {
  // Random layouts whose shaft is stiffer than the bending section (as in
  // catheters; the proximal compression then stays below a few percent):
  // the tip of a reachable configuration solves back to it.
  for (int trial = 0; trial < 100; ++trial) {
    ManipulatorOptions options = testing::RandomOptions(rng_);
    options.stiffness.axial_proximal =
        std::max(options.stiffness.axial_proximal, 3.0 * options.stiffness.axial_distal);
    const TendonModel model(options);
    std::uniform_real_distribution<double> phi(-3.2, 3.2), bend(0.05, 2.0), extra(0.0, 0.01);
    Configuration asked = Configuration::Zero();
    const double direction = phi(rng_), angle = bend(rng_);
    asked.head<2>() = CurvatureTowards(direction, angle, model.lengths().distal);
    // At the floor of eps1 (trial even) or above it.
    const double floor = MinimumDistalStrain(model, asked(0), asked(1), 0.3);
    asked(kStrainDistal) = floor + (trial % 2) * extra(rng_);
    asked(kStrainProximal) = model.ProximalPerDistalStrain() * asked(kStrainDistal);
    const Vec3 tip = BaseFromTip(asked, model.lengths()).translation();
    const TipSolution solved = ConfigurationForTip(model, tip, 0.3);
    EXPECT_LT(solved.residual, 1e-6) << "trial " << trial;
    EXPECT_LT((solved.configuration - asked).head<2>().norm() * model.lengths().distal, 1e-6);
    EXPECT_NEAR(solved.configuration(kStrainDistal), asked(kStrainDistal), 1e-6);
  }
}

TEST_F(TargetResolverTest, TipsOffTheReachableShellAreRejected) {
  const TargetResolver resolver(model_, options_);
  Target target;
  target.kind = TargetKind::kTipPosition;
  // Beyond the manipulator's length, farther aside than the distal section
  // is long, and behind the distal section's start.
  for (const Vec3& tip : {Vec3(0.0, 900.0, 0.0), Vec3(200.0, 650.0, 0.0), Vec3(0.0, 300.0, 0.0)}) {
    target.tip = tip;
    const ResolvedTarget r = resolver.Resolve(target);
    EXPECT_FALSE(r.ok);
    EXPECT_EQ(r.reason.rfind("tip: unreachable, ", 0), 0u) << r.reason;
  }
  target.tip = Vec3(0.0, std::nan(""), 0.0);
  EXPECT_EQ(resolver.Resolve(target).reason, "tip: expected finite numbers");
  // And one on the shell resolves, its tip where asked.
  Target q_target;
  q_target.configuration.head<2>() = CurvatureTowards(1.0, 1.0, model_.lengths().distal);
  const ResolvedTarget reference = resolver.Resolve(q_target);
  target.tip = BaseFromTip(reference.configuration, model_.lengths()).translation();
  const ResolvedTarget r = resolver.Resolve(target);
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_LT(r.tip_residual, 1e-6);
  EXPECT_LT((r.configuration - reference.configuration).norm(), 1e-6);
}

TEST_F(TargetResolverTest, TrajectoriesResolveOrNameTheTargetThatCannot) {
  const TargetResolver resolver(model_, options_);
  const Trajectory good = ParseTrajectoryYaml(
      "targets:\n  - {time: 0, q: [0, 0, 0, 0]}\n  - {time: 2, q: [0.005, 0, 0, 0]}\n", "t");
  const ResolvedTrajectory resolved = ResolveTrajectory(good, resolver, "t.yaml");
  ASSERT_EQ(resolved.targets.size(), 2u);
  const Trajectory bad = ParseTrajectoryYaml(
      "targets:\n  - {time: 0, q: [0, 0, 0, 0]}\n  - {time: 2, q: [0.05, 0, 0, 0]}\n", "t");
  try {
    ResolveTrajectory(bad, resolver, "t.yaml");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("t.yaml: targets[1]: curvature 0.05 /mm beyond"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(TargetResolverTest, TargetAtInterpolatesOrSteps) {
  ResolvedTrajectory trajectory;
  ResolvedTarget a, b;
  a.time = 1.0;
  a.configuration = Configuration(0.001, 0.0, 0.0, 0.002);
  b.time = 3.0;
  b.configuration = Configuration(0.003, -0.002, 0.0, 0.004);
  trajectory.targets = {a, b};
  EXPECT_EQ(TargetAt(trajectory, 0.0), a.configuration);
  EXPECT_EQ(TargetAt(trajectory, 1.0), a.configuration);
  EXPECT_LT((TargetAt(trajectory, 2.0) - (a.configuration + b.configuration) / 2.0).norm(), 1e-15);
  EXPECT_EQ(TargetAt(trajectory, 5.0), b.configuration);
  trajectory.interpolate = false;
  EXPECT_EQ(TargetAt(trajectory, 2.9), a.configuration);
  EXPECT_EQ(TargetAt(trajectory, 3.0), b.configuration);
  EXPECT_THROW(TargetAt(ResolvedTrajectory{}, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace shapesense
