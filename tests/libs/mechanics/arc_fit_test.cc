#include "libs/mechanics/arc_fit.h"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "libs/mechanics/configuration_geometry.h"

namespace shapesense {
namespace {

constexpr SectionLengths kRest{600.0, 160.0};

ArcFitInput InputFor(const Configuration& q, double spacing, double noise, std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, noise);
  ArcFitInput input;
  input.points = DistalCenterline(q, kRest, spacing);
  for (Vec3& p : input.points) p += Vec3(normal(rng), normal(rng), normal(rng));
  const SectionLengths compressed = CompressedLengths(q, kRest);
  input.distal_length = compressed.distal;
  input.proximal_length = compressed.proximal;
  input.rest = kRest;
  return input;
}

Configuration ArcTowards(double phi, double kappa) {
  return {kappa * std::sin(phi), -kappa * std::cos(phi), 0.004, 0.01};
}

double AngleDifference(double a, double b) { return std::remainder(a - b, 2.0 * std::numbers::pi); }

class ArcFitTest : public ::testing::Test {
 protected:
  std::mt19937_64 rng_{12345};
  std::uniform_real_distribution<double> phi_{-std::numbers::pi, std::numbers::pi};
};

TEST_F(ArcFitTest, ExactArcsAreRecoveredExactly) {
  for (const double kappa : {0.0, 1e-4, 0.004, 0.012, 0.025}) {
    const Configuration q = ArcTowards(phi_(rng_), kappa);
    const ArcFit fit = FitCircularArc(InputFor(q, 2.0, 0.0, rng_), ArcFitOptions{});
    ASSERT_TRUE(fit.converged) << fit.message;
    EXPECT_LT((fit.configuration - q).norm(), 1e-9) << kappa;
    EXPECT_LT(fit.rms_residual, 1e-7);
  }
}

TEST_F(ArcFitTest, NoisyFinelySampledArcGivesCurvatureAndPlaneWithinOnePercent) {
  // 0.5 mm spacing (321 points), 0.2 mm noise on every axis: the noisy
  // polyline is ~10% longer than the arc, which an arc-length fit would take
  // for less curvature.
  double worst_kappa = 0.0, worst_phi = 0.0;
  for (int trial = 0; trial < 8; ++trial) {
    const double phi = phi_(rng_), kappa = 0.003 + 0.002 * trial;
    const ArcFit fit =
        FitCircularArc(InputFor(ArcTowards(phi, kappa), 0.5, 0.2, rng_), ArcFitOptions{});
    ASSERT_TRUE(fit.converged) << fit.message;
    worst_kappa = std::max(worst_kappa, std::abs(fit.curvature - kappa) / kappa);
    worst_phi = std::max(worst_phi, std::abs(AngleDifference(fit.bend_direction, phi)));
    // The points' distance to the arc: the noise across the arc, 2 of 3 axes.
    EXPECT_NEAR(fit.rms_residual, 0.2 * std::sqrt(2.0), 0.04);
  }
  EXPECT_LT(worst_kappa, 0.01);
  EXPECT_LT(worst_phi, 0.01);
  RecordProperty("worst_relative_curvature_error", std::to_string(worst_kappa));
  RecordProperty("worst_bend_direction_error_rad", std::to_string(worst_phi));
}

TEST_F(ArcFitTest, ReportedCovarianceMatchesTheSpreadOfTheEstimates) {
  const Configuration q = ArcTowards(0.7, 0.008);
  std::vector<Eigen::Vector2d> estimates;
  Eigen::Matrix2d reported = Eigen::Matrix2d::Zero();
  const int trials = 60;
  for (int trial = 0; trial < trials; ++trial) {
    const ArcFit fit = FitCircularArc(InputFor(q, 1.0, 0.3, rng_), ArcFitOptions{});
    ASSERT_TRUE(fit.converged);
    estimates.push_back(fit.configuration.head<2>());
    reported += fit.covariance.topLeftCorner<2, 2>() / trials;
  }
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& e : estimates) mean += e / trials;
  Eigen::Matrix2d spread = Eigen::Matrix2d::Zero();
  for (const auto& e : estimates) spread += (e - mean) * (e - mean).transpose() / (trials - 1);
  for (int k = 0; k < 2; ++k) {
    const double ratio = std::sqrt(spread(k, k) / reported(k, k));
    RecordProperty("spread_over_reported_std_" + std::to_string(k), std::to_string(ratio));
    EXPECT_GT(ratio, 0.7) << k;
    EXPECT_LT(ratio, 1.4) << k;
    // And the estimate is unbiased to well within its spread.
    EXPECT_LT(std::abs(mean(k) - q(k)), 4.0 * std::sqrt(spread(k, k) / trials)) << k;
  }
}

TEST_F(ArcFitTest, HuberLossKeepsStrayPointsFromPullingTheFit) {
  const double phi = 1.1, kappa = 0.01;
  ArcFitInput input = InputFor(ArcTowards(phi, kappa), 1.0, 0.1, rng_);
  for (size_t i = 5; i + 5 < input.points.size(); i += 20) input.points[i] += Vec3(8.0, -3.0, 6.0);
  const ArcFit fit = FitCircularArc(input, ArcFitOptions{});
  ASSERT_TRUE(fit.converged);
  EXPECT_LT(std::abs(fit.curvature - kappa) / kappa, 0.01);
  EXPECT_LT(std::abs(AngleDifference(fit.bend_direction, phi)), 0.01);
}

TEST_F(ArcFitTest, EstimatesTheBasePoseJointly) {
  for (int trial = 0; trial < 5; ++trial) {
    const double kappa = 0.006 + 0.002 * trial;
    const Configuration q = ArcTowards(phi_(rng_), kappa);
    ArcFitInput input = InputFor(q, 1.0, 0.1, rng_);
    Pose3 world_from_base = Pose3::Identity();
    world_from_base.linear() =
        Eigen::AngleAxisd(phi_(rng_), Vec3::Random().normalized()).toRotationMatrix();
    world_from_base.translation() = Vec3(100.0, -50.0, 400.0) + 20.0 * Vec3::Random();
    for (Vec3& p : input.points) p = world_from_base * p;
    // Initial guess: 4 degrees and 4 mm off.
    input.world_from_base = world_from_base;
    input.world_from_base.linear() =
        Eigen::AngleAxisd(0.07, Vec3::Random().normalized()) * world_from_base.linear();
    input.world_from_base.translation() += Vec3(3.0, -2.0, 2.0);
    ArcFitOptions options;
    options.estimate_base_pose = true;
    const ArcFit fit = FitCircularArc(input, options);
    ASSERT_TRUE(fit.converged) << fit.message;
    EXPECT_LT(std::abs(fit.curvature - kappa) / kappa, 0.01);
    // Axis of the base, and where the arc starts (the base itself is 600 mm
    // further down the axis, so its position carries the axis error times
    // 600 mm); the roll is not observable, so compare the bending direction
    // in the world instead.
    const Vec3 axis = fit.world_from_base.linear().col(1);
    EXPECT_LT(std::acos(std::min(1.0, axis.dot(world_from_base.linear().col(1)))), 0.005);
    const Vec3 arc_start(0.0, input.proximal_length, 0.0);
    EXPECT_LT((fit.world_from_base * arc_start - world_from_base * arc_start).norm(), 0.1);
    const Vec3 bend_fit = fit.world_from_base.linear() *
                          Vec3(-fit.configuration(kKappaZ), 0, fit.configuration(kKappaX));
    const Vec3 bend_true = world_from_base.linear() * Vec3(-q(kKappaZ), 0, q(kKappaX));
    EXPECT_LT((bend_fit - bend_true).norm() / kappa, 0.02);
  }
}

TEST_F(ArcFitTest, StrainsComeFromTheMeasuredLengths) {
  const Configuration q = ArcTowards(0.3, 0.01);
  ArcFitInput input = InputFor(q, 2.0, 0.0, rng_);
  input.distal_length_std = 0.16;
  const ArcFit fit = FitCircularArc(input, ArcFitOptions{});
  EXPECT_NEAR(fit.configuration(kStrainProximal), q(kStrainProximal), 1e-12);
  EXPECT_NEAR(fit.configuration(kStrainDistal), q(kStrainDistal), 1e-12);
  EXPECT_NEAR(std::sqrt(fit.covariance(3, 3)), 0.001, 1e-12);
}

TEST_F(ArcFitTest, RefusesTooFewPoints) {
  ArcFitInput input;
  input.points = {Vec3::Zero(), Vec3::UnitY()};
  input.rest = kRest;
  const ArcFit fit = FitCircularArc(input, ArcFitOptions{});
  EXPECT_FALSE(fit.converged);
  EXPECT_NE(fit.message.find("at least 3 points"), std::string::npos);
}

}  // namespace
}  // namespace shapesense
