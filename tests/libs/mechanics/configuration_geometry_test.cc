#include "libs/mechanics/configuration_geometry.h"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "libs/geometry/polyline.h"

namespace shapesense {
namespace {

constexpr SectionLengths kRest{600.0, 160.0};

Configuration RandomConfiguration(std::mt19937_64& rng, double max_curvature = 0.02) {
  std::uniform_real_distribution<double> curvature(-max_curvature, max_curvature),
      strain(-0.01, 0.03);
  return {curvature(rng), curvature(rng), strain(rng), strain(rng)};
}

class ConfigurationGeometryTest : public ::testing::Test {
 protected:
  std::mt19937_64 rng_{99};
};

TEST_F(ConfigurationGeometryTest, SignConventions) {
  // kappa_x > 0 bends the tip toward +z; kappa_z > 0 toward -x.
  const Vec3 tip_x = BaseFromTip(Configuration(0.005, 0, 0, 0), kRest).translation();
  EXPECT_GT(tip_x.z(), 10.0);
  EXPECT_NEAR(tip_x.x(), 0.0, 1e-12);
  const Vec3 tip_z = BaseFromTip(Configuration(0, 0.005, 0, 0), kRest).translation();
  EXPECT_LT(tip_z.x(), -10.0);
  EXPECT_NEAR(tip_z.z(), 0.0, 1e-12);
  // Straight: the tip on the y axis at the compressed length.
  const Vec3 straight = BaseFromTip(Configuration(0, 0, 0.01, 0.02), kRest).translation();
  EXPECT_LT((straight - Vec3(0.0, 600.0 * 0.99 + 160.0 * 0.98, 0.0)).norm(), 1e-9);
}

TEST_F(ConfigurationGeometryTest, CentrelineHasTheCompressedLength) {
  for (int trial = 0; trial < 100; ++trial) {
    const Configuration q = RandomConfiguration(rng_);
    const SectionLengths compressed = CompressedLengths(q, kRest);
    const Polyline line = CenterlineFromConfiguration(q, kRest, 0.05);
    // A chord of a circle is shorter than its arc by ~ s^3 k^2 / 24 per step.
    EXPECT_NEAR(PolylineLength(line), compressed.proximal + compressed.distal, 1e-4);
    EXPECT_LT((line.back() - BaseFromTip(q, kRest).translation()).norm(), 1e-9);
    for (size_t i = 1; i < line.size(); ++i) EXPECT_LE((line[i] - line[i - 1]).norm(), 0.05 + 1e-9);
  }
}

TEST_F(ConfigurationGeometryTest, DistalPointsLieOnACircleOfRadiusOneOverKappa) {
  for (int trial = 0; trial < 100; ++trial) {
    const Configuration q = RandomConfiguration(rng_);
    const double kappa = q.head<2>().norm();
    const Pose3 start = BaseFromDistalStart(q, kRest);
    // Centre: from the start, 1/kappa along the bend direction (-kappa_z, 0, kappa_x)/kappa.
    const Vec3 centre = start * (Vec3(-q(kKappaZ), 0.0, q(kKappaX)) / (kappa * kappa));
    const Vec3 normal = Vec3(q(kKappaX), 0.0, q(kKappaZ)) / kappa;
    for (const Vec3& p : DistalCenterline(q, kRest, 2.0)) {
      EXPECT_NEAR((p - centre).norm(), 1.0 / kappa, 1e-9 / kappa);
      EXPECT_NEAR((p - centre).dot(normal), 0.0, 1e-9 / kappa);
    }
  }
}

TEST_F(ConfigurationGeometryTest, TipFrameTurnsByTheBendAngleAndFollowsTheTangent) {
  for (int trial = 0; trial < 100; ++trial) {
    // Bends below pi, where the angle of the rotation is the bend angle.
    const Configuration q = RandomConfiguration(rng_, 0.012);
    const double length = CompressedLengths(q, kRest).distal;
    const Pose3 tip = BaseFromTip(q, kRest);
    const double angle = Eigen::AngleAxisd(tip.linear()).angle();
    EXPECT_NEAR(angle, q.head<2>().norm() * length, 1e-9);
    // The tip frame's y axis is the centreline's tangent there.
    const double h = 1e-4;
    const Vec3 tangent =
        (tip.translation() - BaseFromDistalPoint(q, kRest, length - h).translation()) / h;
    EXPECT_LT((tangent - tip.linear().col(1)).norm(), 1e-3);
  }
}

TEST_F(ConfigurationGeometryTest, TurningTheCurvatureVectorTurnsTheShapeAboutTheAxis) {
  for (int trial = 0; trial < 50; ++trial) {
    const Configuration q = RandomConfiguration(rng_);
    std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
    const Eigen::AngleAxisd turn(angle(rng_), Vec3::UnitY());
    const Vec3 turned_kappa = turn * Vec3(q(kKappaX), 0.0, q(kKappaZ));
    const Configuration q_turned(turned_kappa.x(), turned_kappa.z(), q(2), q(3));
    const Polyline a = DistalCenterline(q, kRest, 5.0), b = DistalCenterline(q_turned, kRest, 5.0);
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) EXPECT_LT((turn * a[i] - b[i]).norm(), 1e-9);
  }
}

TEST_F(ConfigurationGeometryTest, NearlyStraightArcsAreContinuous) {
  // Across the switch to the series of sin(t)/t and (1 - cos t)/t^2.
  for (const double kappa : {0.0, 1e-12, 1e-7, 6.2e-6, 6.3e-6, 1e-5, 1e-3}) {
    const Vec3 tip = BaseFromTip(Configuration(kappa, 0, 0, 0), kRest).translation();
    const double theta = kappa * 160.0;
    const double half_sine = std::sin(theta / 2.0);
    const Vec3 exact =
        kappa == 0.0 ? Vec3(0, 760, 0)
                     : Vec3(0, 600 + std::sin(theta) / kappa, 2.0 * half_sine * half_sine / kappa);
    EXPECT_LT((tip - exact).norm(), 1e-10) << kappa;
  }
}

}  // namespace
}  // namespace shapesense
