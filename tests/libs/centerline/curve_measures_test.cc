#include "libs/centerline/curve_measures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "libs/geometry/polyline.h"
#include "tests/libs/centerline/tube_fixture.h"

namespace shapesense {
namespace {

using testing::AppendArc;
using testing::Uniform;

Vec3 RandomUnit(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  return Vec3(normal(rng), normal(rng), normal(rng)).normalized();
}

// Curvature is the turning angle over the length: exact for an arc of any
// radius and length, in any orientation.
TEST(CurvatureTest, IsOneOverTheRadiusOfAnArcFromItsTangents) {
  std::mt19937 rng(20);
  for (int trial = 0; trial < 50; ++trial) {
    const double radius = Uniform(rng, 5.0, 500.0);
    const double length = Uniform(rng, 10.0, std::min(300.0, 1.9 * std::numbers::pi * radius));
    const Vec3 a = RandomUnit(rng);
    const Vec3 b = (RandomUnit(rng).cross(a)).normalized();
    const auto tangent = [&](double s) {
      return Vec3(std::cos(s / radius) * a + std::sin(s / radius) * b);
    };
    std::vector<double> at;
    for (double s = 0.0; s <= length; s += Uniform(rng, 0.2, 3.0)) at.push_back(s);
    const double window = Uniform(rng, 2.0, 20.0);
    for (const double k : CurvatureByTurningAngle(at, length, tangent, window)) {
      EXPECT_NEAR(k * radius, 1.0, 1e-9);
    }
  }
}

TEST(CurvatureTest, IsOneOverTheRadiusAlongAFinelySampledArc) {
  std::mt19937 rng(9);
  for (int trial = 0; trial < 50; ++trial) {
    const double radius = Uniform(rng, 8.0, 500.0);
    const double length = Uniform(rng, 20.0, std::min(300.0, 1.9 * std::numbers::pi * radius));
    const Vec3 direction = RandomUnit(rng);
    Polyline arc_points = {Vec3(Uniform(rng, -50, 50), Uniform(rng, -50, 50), 0.0)};
    Vec3 d = direction;
    AppendArc(&arc_points, &d, RandomUnit(rng), length, length / radius, 0.1);
    // Chords of a polyline stray from the arc by spacing² / 8R.
    const Polyline points = ResampleUniform(arc_points, 0.02 * std::sqrt(radius));
    const std::vector<double> arc = CumulativeArcLength(points);
    const std::vector<double> curvature =
        CurvatureByTurningAngle(points, arc, Uniform(rng, 4.0, 15.0));
    ASSERT_EQ(curvature.size(), points.size());
    for (const double k : curvature) EXPECT_NEAR(k * radius, 1.0, 2e-3) << "radius " << radius;
  }
}

TEST(CurvatureTest, IsZeroAlongAStraightLine) {
  std::mt19937 rng(10);
  for (int trial = 0; trial < 10; ++trial) {
    const Vec3 start(Uniform(rng, -50, 50), Uniform(rng, -50, 50), Uniform(rng, -50, 50));
    const Vec3 direction = RandomUnit(rng);
    Polyline points;
    for (double s = 0.0; s <= Uniform(rng, 10.0, 200.0); s += 1.0)
      points.push_back(start + s * direction);
    const std::vector<double> arc = CumulativeArcLength(points);
    for (const double k : CurvatureByTurningAngle(points, arc, 10.0)) EXPECT_NEAR(k, 0.0, 1e-9);
  }
}

TEST(CurvatureTest, FollowsAChangeOfCurvatureWithinTheWindow) {
  // Straight 60 mm, then an arc of radius 25 mm.
  Polyline points = {Vec3::Zero()};
  Vec3 d = Vec3::UnitZ();
  AppendArc(&points, &d, Vec3::UnitX(), 60.0, 0.0, 0.5);
  AppendArc(&points, &d, Vec3::UnitX(), 60.0, 60.0 / 25.0, 0.5);
  const std::vector<double> arc = CumulativeArcLength(points);
  const double window = 10.0;
  const std::vector<double> curvature = CurvatureByTurningAngle(points, arc, window);
  for (size_t i = 0; i < points.size(); ++i) {
    // The tangents sit window/2 either side and are chords window/2 long.
    const double reach = 0.5 * window + 0.25 * window;
    if (arc[i] < 60.0 - reach) {
      EXPECT_NEAR(curvature[i], 0.0, 1e-9);
    } else if (arc[i] > 60.0 + reach) {
      EXPECT_NEAR(curvature[i], 1.0 / 25.0, 1e-4);
    }
  }
}

TEST(CurvatureTest, IsZeroForCurvesTooShortToMeasure) {
  const Polyline points = {Vec3::Zero(), Vec3(1, 0, 0), Vec3(1, 1, 0)};
  const std::vector<double> arc = CumulativeArcLength(points);
  for (const double k : CurvatureByTurningAngle(points, arc, 10.0)) EXPECT_EQ(k, 0.0);
  EXPECT_TRUE(CurvatureByTurningAngle({}, {}, 10.0).empty());
}

TEST(ChordTangentTest, IsTheTangentOfAnArc) {
  Polyline points = {Vec3::Zero()};
  Vec3 d = Vec3::UnitY();
  AppendArc(&points, &d, Vec3::UnitX(), 50.0, 1.0, 0.05);
  const std::vector<double> arc = CumulativeArcLength(points);
  for (double s = 5.0; s <= 45.0; s += 5.0) {
    const double angle = s / 50.0;
    const Vec3 expected(std::sin(angle), std::cos(angle), 0.0);
    EXPECT_LT((ChordTangent(points, arc, s, 3.0) - expected).norm(), 1e-4);
  }
}

}  // namespace
}  // namespace shapesense
