#include <gtest/gtest.h>

#include <random>

#include "libs/geometry/polyline.h"
#include "libs/sim/scene_generators.h"
#include "tests/libs/sim/sim_test_util.h"

namespace shapesense {
namespace {

// Curvature vector at vertex i: towards the centre of the circle through
// points i-1, i, i+1, with length 1/radius (exact for points on a circle).
Vec3 CurvatureVector(const Polyline& line, size_t i) {
  const Vec3 a = line[i - 1] - line[i];
  const Vec3 b = line[i + 1] - line[i];
  const Vec3 normal = a.cross(b);
  if (normal.squaredNorm() < 1e-24) return Vec3::Zero();
  // Circumcentre relative to line[i].
  const Vec3 center =
      (a.squaredNorm() * b - b.squaredNorm() * a).cross(normal) / (2.0 * normal.squaredNorm());
  return center / center.squaredNorm();
}

TEST(ArcCenterlineTest, HasTheRequestedLengthAndConstantCurvature) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> length(20.0, 300.0), angle(0.05, 3.0), coord(-100, 100);
  for (int trial = 0; trial < 40; ++trial) {
    const Vec3 base(coord(rng), coord(rng), coord(rng));
    const Vec3 direction = testing::RandomUnit(rng);
    const double arc_length = length(rng);
    const double bend = angle(rng);
    const double spacing = 0.25 + 0.5 * (trial % 2);
    const Polyline line =
        ArcCenterline(base, direction, testing::RandomUnit(rng), 0.0, arc_length, bend, spacing);
    // The chords of a polyline are shorter than the arc by ~ h³κ²/24 each.
    const double kappa = bend / arc_length;
    const double chord_deficit = arc_length * spacing * spacing * kappa * kappa / 24.0;
    EXPECT_NEAR(PolylineLength(line), arc_length, 2.0 * chord_deficit + 1e-9);
    EXPECT_LT((line.front() - base).norm(), 1e-12);
    EXPECT_GT((line[1] - line[0]).normalized().dot(direction), std::cos(spacing * kappa));
    for (size_t i = 1; i < line.size(); ++i) {
      EXPECT_LE((line[i] - line[i - 1]).norm(), spacing + 1e-9);
    }
    for (size_t i = 1; i + 1 < line.size(); i += 7) {
      EXPECT_NEAR(CurvatureVector(line, i).norm(), kappa, 1e-6 * kappa) << "vertex " << i;
    }
  }
}

TEST(ArcCenterlineTest, StraightPartHasNoCurvatureAndTheArcTurnsTowardsTheBend) {
  const Vec3 bend_direction(1.0, 0.0,
                            0.3);  // not perpendicular: only its perpendicular part counts
  const Polyline line =
      ArcCenterline(Vec3::Zero(), Vec3::UnitZ(), bend_direction, 30.0, 100.0, 1.0, 0.25);
  const std::vector<double> arc = CumulativeArcLength(line);
  for (size_t i = 1; i + 1 < line.size(); ++i) {
    const Vec3 k = CurvatureVector(line, i);
    if (arc[i] < 29.9) {
      EXPECT_LT(k.norm(), 1e-9);
    } else if (arc[i] > 30.1) {
      EXPECT_GT(k.normalized().dot(Vec3::UnitX()), 0.0);
    }
  }
  EXPECT_NEAR(line.back().y(), 0.0, 1e-9);  // stays in the bending plane
  const Vec3 end_tangent = (line.back() - line[line.size() - 2]).normalized();
  EXPECT_NEAR(std::acos(end_tangent.z()), 1.0, 0.01);
}

TEST(SCurveCenterlineTest, CurvatureChangesSignHalfway) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> length(40.0, 120.0), angle(0.2, 1.5), twist(-1.2, 1.2);
  for (int trial = 0; trial < 20; ++trial) {
    const double each = length(rng);
    const double bend = angle(rng);
    const Polyline line = SCurveCenterline(Vec3::Zero(), testing::RandomUnit(rng),
                                           testing::RandomUnit(rng), each, bend, twist(rng));
    EXPECT_NEAR(PolylineLength(line), 2.0 * each, 1e-3);
    const std::vector<double> arc = CumulativeArcLength(line);
    Vec3 first_half = Vec3::Zero();
    for (size_t i = 1; i + 1 < line.size(); ++i) {
      if (std::abs(arc[i] - each) < 1.0) continue;  // the joint
      const Vec3 k = CurvatureVector(line, i);
      EXPECT_NEAR(k.norm(), bend / each, 1e-6 * bend / each + 1e-9);
      if (arc[i] < each) {
        first_half = k;
      } else {
        // The curvature vector has turned by the tangent's rotation only, so it
        // now points against where it pointed at the end of the first arc.
        const Vec3 tangent = (line[i + 1] - line[i - 1]).normalized();
        const Vec3 carried = first_half - first_half.dot(tangent) * tangent;
        EXPECT_LT(k.dot(carried), 0.0) << "trial " << trial << " s " << arc[i];
        break;
      }
    }
  }
}

}  // namespace
}  // namespace shapesense
