#include "libs/geometry/polyline.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace shapesense {
namespace {

Polyline QuarterCircle(double radius, int n) {
  Polyline points;
  for (int i = 0; i <= n; ++i) {
    const double a = 0.5 * std::numbers::pi * i / n;
    points.emplace_back(radius * std::cos(a), radius * std::sin(a), 0.0);
  }
  return points;
}

TEST(PolylineTest, ArcLengthOfAFineCircleApproachesItsLength) {
  const double length = PolylineLength(QuarterCircle(50.0, 2000));
  EXPECT_NEAR(length, 0.5 * std::numbers::pi * 50.0, 1e-3);
}

TEST(PolylineTest, ResamplingKeepsEndsAndSpacing) {
  const Polyline points = QuarterCircle(50.0, 37);
  const Polyline resampled = ResampleUniform(points, 2.0);
  EXPECT_TRUE(resampled.front().isApprox(points.front()));
  EXPECT_TRUE(resampled.back().isApprox(points.back()));
  for (size_t i = 1; i < resampled.size(); ++i) {
    EXPECT_LE((resampled[i] - resampled[i - 1]).norm(), 2.0 + 1e-9);
  }
  EXPECT_NEAR(PolylineLength(resampled), PolylineLength(points), 0.05);
}

TEST(PolylineTest, PointAtArcLengthInvertsTheClosestPointQuery) {
  const Polyline points = QuarterCircle(30.0, 50);
  const std::vector<double> arc = CumulativeArcLength(points);
  for (double s = 0.0; s <= arc.back(); s += 3.7) {
    const Vec3 p = PointAtArcLength(points, arc, s);
    const ClosestPoint closest = ClosestPointOnPolyline(points, arc, p);
    EXPECT_NEAR(closest.arc_length, s, 1e-9);
    EXPECT_NEAR(closest.distance, 0.0, 1e-9);
  }
}

TEST(PolylineTest, RmsDistanceMeasuresAConstantOffset) {
  Polyline truth = {Vec3(0, 0, 0), Vec3(0, 0, 100)};
  Polyline shifted = {Vec3(0.5, 0, 10), Vec3(0.5, 0, 50), Vec3(0.5, 0, 90)};
  EXPECT_NEAR(RmsDistanceToPolyline(shifted, truth), 0.5, 1e-12);
  EXPECT_TRUE(std::isnan(RmsDistanceToPolyline({}, truth)));
}

}  // namespace
}  // namespace shapesense
