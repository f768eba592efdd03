#include "libs/mechanics/tendon_model.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <random>

#include "tests/libs/mechanics/test_models.h"

namespace shapesense {
namespace {

Eigen::VectorXd RandomVector(int size, double scale, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Eigen::VectorXd v(size);
  for (int i = 0; i < size; ++i) v(i) = u(rng);
  return v;
}

// A configuration the model can reach: eps0 follows eps1.
Configuration ReachableConfiguration(const TendonModel& model, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> curvature(-0.01, 0.01), strain(-0.002, 0.01);
  Configuration q(curvature(rng), curvature(rng), 0.0, strain(rng));
  q(kStrainProximal) = model.ProximalPerDistalStrain() * q(kStrainDistal);
  return q;
}

class TendonModelPropertyTest : public ::testing::Test {
 protected:
  std::mt19937_64 rng_{20240611};
};

TEST_F(TendonModelPropertyTest, ColumnsOfDAreTheTendonsMomentArms) {
  const TendonModel model(testing::CatheterOptions());
  for (int i = 0; i < model.num_tendons(); ++i) {
    const TendonOptions& t = model.options().tendons[static_cast<size_t>(i)];
    EXPECT_EQ(model.moment_arms().col(i), Eigen::Vector4d(t.dz, -t.dx, 1.0, 1.0));
  }
  EXPECT_EQ(model.configuration_lengths(), Eigen::Vector4d(160.0, 160.0, 600.0, 160.0));
}

TEST_F(TendonModelPropertyTest, ComplianceIsSymmetricPositiveDefinite) {
  for (int trial = 0; trial < 100; ++trial) {
    const TendonModel model(testing::RandomOptions(rng_));
    const Eigen::MatrixXd& c = model.displacement_compliance();
    EXPECT_LT((c - c.transpose()).norm(), 1e-12 * c.norm());
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(c).eigenvalues().minCoeff(), 0.0);
  }
}

TEST_F(TendonModelPropertyTest, ForwardSolutionsBalanceForcesAndMatchTendonLengths) {
  for (int trial = 0; trial < 200; ++trial) {
    const TendonModel model(testing::RandomOptions(rng_));
    const Eigen::VectorXd y = RandomVector(model.num_tendons(), 5.0, rng_);
    const TendonState state = model.Solve(y);
    const Configuration& q = state.configuration;
    // Equilibrium K_m q = D tau.
    const Eigen::Vector4d generalized_force = model.moment_arms() * state.tensions;
    EXPECT_LT((model.stiffness().cwiseProduct(q) - generalized_force).norm(),
              1e-9 * (generalized_force.norm() + 1.0));
    // Compatibility y = D^T L0 q + L_t K_t^-1 tau.
    const Eigen::VectorXd path =
        model.moment_arms().transpose() * model.configuration_lengths().asDiagonal() * q;
    const Eigen::VectorXd stretch = model.tendon_compliance().cwiseProduct(state.tensions);
    EXPECT_LT((path + stretch - y).norm(), 1e-9 * y.norm());
    // q = A y, and eps0 follows eps1.
    EXPECT_LT((model.Forward(y) - q).norm(), 1e-9 * q.norm());
    EXPECT_NEAR(q(kStrainProximal), model.ProximalPerDistalStrain() * q(kStrainDistal),
                1e-9 * std::abs(q(kStrainProximal)) + 1e-15);
    // The tendons do positive work on the manipulator: y . tau = tau^T C_m tau > 0.
    EXPECT_GT(y.dot(state.tensions), 0.0);
  }
}

TEST_F(TendonModelPropertyTest, SlackIsFlaggedExactlyWhenATensionIsNegative) {
  int slack_seen = 0, taut_seen = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const TendonModel model(testing::RandomOptions(rng_));
    const TendonState state = model.Solve(RandomVector(model.num_tendons(), 5.0, rng_));
    for (int i = 0; i < model.num_tendons(); ++i) {
      const bool flagged = std::find(state.slack_tendons.begin(), state.slack_tendons.end(), i) !=
                           state.slack_tendons.end();
      EXPECT_EQ(flagged, state.tensions(i) < 0.0) << "tendon " << i;
      (flagged ? slack_seen : taut_seen)++;
    }
  }
  EXPECT_GT(slack_seen, 100);
  EXPECT_GT(taut_seen, 100);
}

TEST_F(TendonModelPropertyTest, InverseThenForwardGivesTheDesiredConfiguration) {
  for (int trial = 0; trial < 200; ++trial) {
    const TendonModel model(testing::RandomOptions(rng_));
    const Configuration desired = ReachableConfiguration(model, rng_);
    const InverseSolution inverse = model.Inverse(desired);
    ASSERT_TRUE(inverse.feasible);
    EXPECT_LT((model.Forward(inverse.displacements) - desired).norm(), 1e-9 * desired.norm());
    EXPECT_LT((inverse.state.configuration - desired).norm(), 1e-9 * desired.norm());
  }
}

TEST_F(TendonModelPropertyTest, ForwardThenInverseRecoversTheDisplacementsUpToTheNullSpace) {
  for (int trial = 0; trial < 200; ++trial) {
    const TendonModel model(testing::RandomOptions(rng_));
    const Eigen::VectorXd y = RandomVector(model.num_tendons(), 5.0, rng_);
    const Eigen::VectorXd back = model.Inverse(model.Forward(y)).displacements;
    // The difference moves nothing, and the least-norm answer is the shortest.
    EXPECT_LT((model.actuation() * (back - y)).norm(), 1e-9 * model.Forward(y).norm());
    EXPECT_LE(back.norm(), y.norm() * (1.0 + 1e-12));
  }
}

TEST_F(TendonModelPropertyTest, LeastNormInverseIsThePseudoInverseSolution) {
  for (int trial = 0; trial < 200; ++trial) {
    const TendonModel model(testing::RandomOptions(rng_));
    const Configuration desired = ReachableConfiguration(model, rng_);
    const Eigen::VectorXd y = model.Inverse(desired).displacements;
    // The full 4-row A has rank 3 (the eps0 row is a multiple of the eps1
    // row), so its pseudo-inverse gives the least-norm solution directly.
    // (SVD: Eigen 3.4's CompleteOrthogonalDecomposition::pseudoInverse gets
    // rank-deficient wide matrices wrong.)
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(model.actuation(),
                                          Eigen::ComputeFullU | Eigen::ComputeFullV);
    svd.setThreshold(1e-10);
    ASSERT_EQ(svd.rank(), 3);
    const Eigen::VectorXd pinv_y = svd.solve(desired);
    EXPECT_LT((y - pinv_y).norm(), 1e-8 * pinv_y.norm());
  }
}

TEST_F(TendonModelPropertyTest, InverseIgnoresTheDesiredProximalStrain) {
  const TendonModel model(testing::CatheterOptions());
  Configuration desired(0.005, -0.002, 0.0, 0.003);
  const Eigen::VectorXd y = model.Inverse(desired).displacements;
  desired(kStrainProximal) = 0.5;  // unreachable: eps0 follows eps1
  EXPECT_EQ(model.Inverse(desired).displacements, y);
  EXPECT_NEAR(model.Forward(y)(kStrainProximal), 0.003 * 800.0 / 2500.0, 1e-12);
}

TEST_F(TendonModelPropertyTest, SlackAwareSolveIsComplementary) {
  int with_slack = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const TendonModel model(testing::RandomOptions(rng_));
    const Eigen::VectorXd y = RandomVector(model.num_tendons(), 5.0, rng_);
    const TendonState linear = model.Solve(y);
    const TendonState state = model.SolveWithSlack(y);
    const double scale = y.cwiseAbs().maxCoeff();
    const Eigen::VectorXd excess = model.displacement_compliance() * state.tensions - y;
    EXPECT_GE(state.tensions.minCoeff(), -1e-12 * scale);
    EXPECT_GE(excess.minCoeff(), -1e-9 * scale);
    EXPECT_LT(state.tensions.cwiseProduct(excess).cwiseAbs().maxCoeff(), 1e-9 * scale * scale);
    // Equilibrium still holds with the tensions that remain.
    EXPECT_LT(
        (model.stiffness().cwiseProduct(state.configuration) - model.moment_arms() * state.tensions)
            .norm(),
        1e-9 * (state.tensions.norm() + 1.0));
    if (!linear.has_slack()) {
      EXPECT_LT((state.tensions - linear.tensions).norm(), 1e-9 * linear.tensions.norm());
      EXPECT_TRUE(state.slack_tendons.empty());
    } else {
      ++with_slack;
    }
  }
  EXPECT_GT(with_slack, 50);
}

TEST_F(TendonModelPropertyTest, MinimumTensionInverseKeepsEveryTendonTaut) {
  for (int trial = 0; trial < 100; ++trial) {
    const TendonModel model(testing::RandomOptions(rng_));
    const Configuration desired = ReachableConfiguration(model, rng_);
    std::uniform_real_distribution<double> floor_dist(0.0, 3.0);
    const double floor = floor_dist(rng_);
    const InverseSolution solution = model.InverseWithMinimumTension(desired, floor);
    ASSERT_TRUE(solution.feasible);
    const TendonState& state = solution.state;
    EXPECT_GE(state.tensions.minCoeff(), floor - 1e-7 * (1.0 + floor));
    EXPECT_NEAR(state.configuration(kKappaX), desired(kKappaX), 1e-8 * desired.norm());
    EXPECT_NEAR(state.configuration(kKappaZ), desired(kKappaZ), 1e-8 * desired.norm());
    EXPECT_GE(state.configuration(kStrainDistal), desired(kStrainDistal) - 1e-9);
    // It costs at least as much displacement as the unconstrained inverse of
    // what it achieves.
    const double least = model.Inverse(state.configuration).displacements.norm();
    EXPECT_GE(solution.displacements.norm(), least * (1.0 - 1e-9));
  }
}

TEST_F(TendonModelPropertyTest, MinimumTensionInverseEqualsTheInverseWhenItIsAlreadyTaut) {
  const TendonModel model(testing::CatheterOptions());
  // Enough compression that every tendon pulls: the unconstrained inverse is taut.
  const Configuration desired(0.002, -0.001, 0.0, 0.01);
  const InverseSolution plain = model.Inverse(desired);
  ASSERT_GT(plain.state.tensions.minCoeff(), 0.5);
  const InverseSolution floored = model.InverseWithMinimumTension(desired, 0.5);
  EXPECT_LT((floored.displacements - plain.displacements).norm(),
            1e-9 * plain.displacements.norm());
}

TEST_F(TendonModelPropertyTest, ArticulationsBendTowardEachTendon) {
  for (int trial = 0; trial < 30; ++trial) {
    const TendonModel model(testing::RandomOptions(rng_));
    const std::vector<Eigen::VectorXd> moves = TendonArticulations(model, 0.8, 0.3);
    ASSERT_EQ(static_cast<int>(moves.size()), model.num_tendons());
    for (int i = 0; i < model.num_tendons(); ++i) {
      const TendonState state = model.Solve(moves[static_cast<size_t>(i)]);
      const TendonOptions& t = model.options().tendons[static_cast<size_t>(i)];
      // The tip moves toward (-kappa_z, kappa_x) in the x-z plane.
      const Eigen::Vector2d toward(-state.configuration(kKappaZ), state.configuration(kKappaX));
      EXPECT_NEAR(toward.normalized().dot(Eigen::Vector2d(t.dx, t.dz).normalized()), 1.0, 1e-9);
      EXPECT_NEAR(toward.norm() * model.lengths().distal, 0.8, 1e-8);
      EXPECT_GE(state.tensions.minCoeff(), 0.3 - 1e-7);
    }
  }
}

TEST(TendonModelTest, RejectsInvalidOptions) {
  ManipulatorOptions options = testing::CatheterOptions();
  options.tendons.pop_back();
  options.tendons.pop_back();
  EXPECT_THROW(TendonModel{options}, std::invalid_argument);
}

}  // namespace
}  // namespace shapesense
