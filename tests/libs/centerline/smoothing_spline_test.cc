#include "libs/centerline/smoothing_spline.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "libs/geometry/polyline.h"
#include "tests/libs/centerline/tube_fixture.h"

namespace shapesense {
namespace {

using testing::Uniform;

// A random quadratic space curve and its derivatives.
struct Quadratic {
  Vec3 a, b, c;
  Vec3 At(double u) const { return a + u * b + u * u * c; }
  Vec3 Derivative(double u) const { return b + 2.0 * u * c; }
};

Quadratic RandomQuadratic(std::mt19937& rng) {
  const auto v = [&rng](double scale) {
    return Vec3(Uniform(rng, -scale, scale), Uniform(rng, -scale, scale),
                Uniform(rng, -scale, scale));
  };
  return {v(50.0), v(1.0), v(0.01)};
}

// The penalty on c''' vanishes on quadratics, and the B-splines hold them:
// the fit reproduces a quadratic exactly, whatever the smoothing.
TEST(SmoothingSplineTest, ReproducesQuadraticsAtAnySmoothing) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const Quadratic curve = RandomQuadratic(rng);
    std::vector<double> u;
    Polyline points;
    for (double x = Uniform(rng, -20, 0); x < 80.0; x += Uniform(rng, 0.3, 3.0)) {
      u.push_back(x);
      points.push_back(curve.At(x));
    }
    const double smoothing = Uniform(rng, 0.0, 10.0);
    const SmoothingSpline spline =
        SmoothingSpline::Fit(u, points, {}, Uniform(rng, 2.0, 12.0), smoothing);
    ASSERT_FALSE(spline.empty());
    EXPECT_DOUBLE_EQ(spline.begin(), u.front());
    EXPECT_NEAR(spline.end(), u.back(), 1e-9);
    for (double x = u.front(); x <= u.back(); x += 0.37) {
      EXPECT_LT((spline.Point(x) - curve.At(x)).norm(), 1e-6) << "smoothing " << smoothing;
      EXPECT_LT((spline.Derivative(x) - curve.Derivative(x)).norm(), 1e-6);
      EXPECT_LT((spline.SecondDerivative(x) - 2.0 * curve.c).norm(), 1e-6);
    }
  }
}

TEST(SmoothingSplineTest, ContinuesAlongItsEndTangents) {
  std::mt19937 rng(6);
  const Quadratic curve = RandomQuadratic(rng);
  std::vector<double> u;
  Polyline points;
  for (double x = 0.0; x <= 40.0; x += 1.0) {
    u.push_back(x);
    points.push_back(curve.At(x));
  }
  const SmoothingSpline spline = SmoothingSpline::Fit(u, points, {}, 5.0, 1.0);
  for (const double beyond : {0.5, 3.0, 10.0}) {
    EXPECT_LT(
        (spline.Point(40.0 + beyond) - (curve.At(40.0) + beyond * curve.Derivative(40.0))).norm(),
        1e-6);
    EXPECT_LT((spline.Point(-beyond) - (curve.At(0.0) - beyond * curve.Derivative(0.0))).norm(),
              1e-6);
  }
}

TEST(SmoothingSplineTest, AveragesNoiseAwayOnACircle) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.2);
  const double radius = 40.0;
  std::vector<double> u;
  Polyline points;
  for (double s = 0.0; s <= 100.0; s += 1.0) {
    u.push_back(s);
    points.emplace_back(radius * std::cos(s / radius) + noise(rng),
                        radius * std::sin(s / radius) + noise(rng), noise(rng));
  }
  const SmoothingSpline spline = SmoothingSpline::Fit(u, points, {}, 5.0, 3.0);
  double sum_sq = 0.0;
  int n = 0;
  for (double s = 5.0; s <= 95.0; s += 0.5, ++n) {
    const Vec3 p = spline.Point(s);
    sum_sq += std::pow(std::hypot(p.x(), p.y()) - radius, 2) + p.z() * p.z();
  }
  // Well below the 0.35 mm (3-D) of the points: a knot span holds five.
  EXPECT_LT(std::sqrt(sum_sq / n), 0.4 * std::sqrt(3.0) * 0.2);
}

TEST(SmoothingSplineTest, WeightsLetGoodPointsOverruleBadOnes) {
  std::vector<double> u;
  Polyline points;
  std::vector<double> weights;
  for (double s = 0.0; s <= 50.0; s += 1.0) {
    u.push_back(s);
    const bool bad = static_cast<int>(s) % 3 == 0;
    points.emplace_back(s, bad ? 5.0 : 0.0, 0.0);
    weights.push_back(bad ? 1e-4 : 1.0);
  }
  const SmoothingSpline spline = SmoothingSpline::Fit(u, points, weights, 5.0, 1.0);
  for (double s = 0.0; s <= 50.0; s += 0.5) EXPECT_NEAR(spline.Point(s).y(), 0.0, 0.01);
}

TEST(SmoothingSplineTest, RefusesDataThatCannotDefineACurve) {
  EXPECT_TRUE(SmoothingSpline::Fit({}, {}, {}, 5.0, 1.0).empty());
  EXPECT_TRUE(SmoothingSpline::Fit({1.0, 1.0}, {Vec3::Zero(), Vec3::Ones()}, {}, 5.0, 1.0).empty());
  EXPECT_TRUE(
      SmoothingSpline::Fit({0.0, 1.0}, {Vec3::Zero(), Vec3::Ones()}, {1.0, 0.0}, 5.0, 1.0).empty());
  EXPECT_TRUE(SmoothingSpline::Fit({0.0, 1.0}, {Vec3::Zero()}, {}, 5.0, 1.0).empty());
  EXPECT_FALSE(
      SmoothingSpline::Fit({0.0, 1.0}, {Vec3::Zero(), Vec3::Ones()}, {}, 5.0, 1.0).empty());
}

TEST(SampleByArcLengthTest, SpacesPointsEvenlyUpToTheSpacing) {
  std::mt19937 rng(8);
  for (int trial = 0; trial < 10; ++trial) {
    const Quadratic curve = RandomQuadratic(rng);
    std::vector<double> u;
    Polyline points;
    for (double x = 0.0; x <= 60.0; x += 2.0) {
      u.push_back(x);
      points.push_back(curve.At(x));
    }
    const SmoothingSpline spline = SmoothingSpline::Fit(u, points, {}, 6.0, 1.0);
    const double spacing = Uniform(rng, 0.3, 2.0);
    std::vector<double> params;
    const Polyline sampled = SampleByArcLength(spline, 3.0, 57.0, spacing, &params);
    ASSERT_EQ(params.size(), sampled.size());
    EXPECT_NEAR(params.front(), 3.0, 1e-9);
    EXPECT_NEAR(params.back(), 57.0, 1e-9);
    const std::vector<double> arc = CumulativeArcLength(sampled);
    const double step = arc.back() / static_cast<double>(sampled.size() - 1);
    EXPECT_LE(step, spacing + 1e-9);
    EXPECT_GT(step, spacing * 0.9);
    for (size_t i = 1; i < sampled.size(); ++i) {
      EXPECT_NEAR(arc[i] - arc[i - 1], step, 0.01 * step);
      EXPECT_LT((sampled[i] - spline.Point(params[i])).norm(), 1e-12);
    }
  }
}

}  // namespace
}  // namespace shapesense
