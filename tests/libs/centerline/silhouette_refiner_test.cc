#include "libs/centerline/silhouette_refiner.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "libs/geometry/polyline.h"
#include "tests/libs/centerline/tube_fixture.h"

namespace shapesense {
namespace {

using testing::ArcTube;
using testing::FixtureRig;
using testing::RenderSilhouettes;
using testing::SilhouetteStyle;
using testing::Uniform;

// The axis as the refiner sees it: a spline through the true points, so
// parameters are arc lengths.
SmoothingSpline AxisSpline(const Polyline& axis) {
  const Polyline points = ResampleUniform(axis, 1.0);
  return SmoothingSpline::Fit(CumulativeArcLength(points), points, {}, 3.0, 0.0);
}

// The axis point refined from a start displaced across the axis by up to
// 1 mm, along with the true point.
struct Refined {
  AxisPointFit fit;
  Vec3 truth;
  int edges = 0;
};

Refined RefineAt(const SilhouetteRefiner& refiner, const SmoothingSpline& axis, double s,
                 double radius, bool estimate_radius, std::mt19937& rng) {
  const Vec3 truth = axis.Point(s);
  const Vec3 t = axis.Derivative(s).normalized();
  Vec3 offset(Uniform(rng, -1, 1), Uniform(rng, -1, 1), Uniform(rng, -1, 1));
  offset -= offset.dot(t) * t;
  // The refiner searches around the displaced curve, as it would around a
  // first estimate that is off by that much.
  std::vector<double> u;
  Polyline shifted;
  for (double x = axis.begin(); x <= axis.end(); x += 1.0) {
    u.push_back(x);
    shifted.push_back(axis.Point(x) + offset);
  }
  const SmoothingSpline start = SmoothingSpline::Fit(u, shifted, {}, 3.0, 0.0);
  std::vector<EdgeConstraint> edges;
  refiner.FindEdges(start, s, start.begin(), start.end(), radius * (estimate_radius ? 1.1 : 1.0),
                    2.0, &edges);
  Refined out;
  out.edges = static_cast<int>(edges.size());
  out.fit = refiner.FitAxisPoint(truth + offset, t, radius, estimate_radius, edges);
  out.truth = truth;
  return out;
}

TEST(SilhouetteRefinerTest, RecoversTheAxisOfAStraightTubeAcrossItsTangent) {
  const Rig rig = FixtureRig(3);
  const Polyline axis =
      ArcTube(rig.base_point, Vec3(0.3, 0.1, 1.0), Vec3::UnitX(), 150.0, 1.0, 0.0);
  const double radius = 3.0;
  const std::vector<Silhouette> silhouettes = RenderSilhouettes(rig, axis, radius, {}, {}, 1);
  const SilhouetteRefiner refiner(rig, silhouettes);
  const SmoothingSpline spline = AxisSpline(axis);
  std::mt19937 rng(15);
  for (double s = 10.0; s < 140.0; s += 7.0) {
    const Refined r = RefineAt(refiner, spline, s, radius, false, rng);
    EXPECT_EQ(r.edges, 6) << "s " << s;
    ASSERT_TRUE(r.fit.ok) << "s " << s;
    // Bilinear sampling places an edge to about 0.05 px (0.03 mm here).
    EXPECT_LT((r.fit.point - r.truth).norm(), 0.08) << "s " << s;
    EXPECT_LT(std::sqrt(r.fit.sum_sq_residual / r.fit.edges_used), 0.06);
  }
}

// Each point gives a radius; their median is the estimate (a few points
// see another part of the tube beside theirs in some camera).
TEST(SilhouetteRefinerTest, EstimatesTheRadiusWithTheAxis) {
  const Rig rig = FixtureRig(3);
  std::mt19937 rng(16);
  for (int trial = 0; trial < 4; ++trial) {
    const double radius = Uniform(rng, 2.0, 5.0);
    const Polyline axis =
        ArcTube(rig.base_point, Vec3::UnitZ(), Vec3(Uniform(rng, -1, 1), 1.0, 0.0), 30.0, 100.0,
                Uniform(rng, 0.5, 1.5));
    const std::vector<Silhouette> silhouettes = RenderSilhouettes(rig, axis, radius, {}, {}, trial);
    const SilhouetteRefiner refiner(rig, silhouettes);
    const SmoothingSpline spline = AxisSpline(axis);
    std::vector<double> radii;
    int close = 0;
    for (double s = 10.0; s < 120.0; s += 5.0) {
      const Refined r = RefineAt(refiner, spline, s, radius, true, rng);
      if (!r.fit.ok) continue;  // e.g. a camera sees the axis end-on
      radii.push_back(r.fit.radius);
      close += (r.fit.point - r.truth).norm() < 0.1 && std::abs(r.fit.radius - radius) < 0.1;
    }
    ASSERT_GE(radii.size(), 12u);
    std::nth_element(radii.begin(), radii.begin() + static_cast<long>(radii.size() / 2),
                     radii.end());
    EXPECT_NEAR(radii[radii.size() / 2], radius, 0.03);
    EXPECT_GE(close, static_cast<int>(0.8 * static_cast<double>(radii.size())));
  }
}

// In a bend seen obliquely the outline comes from cross-sections millimetres
// away from the one walked from; the closest approach of each edge's ray to
// the curve accounts for it.
TEST(SilhouetteRefinerTest, HoldsInTightBendsSeenObliquely) {
  const Rig rig = FixtureRig(3);
  const double radius = 3.5;
  const Polyline axis = ArcTube(rig.base_point, Vec3::UnitZ(), Vec3(0.8, 0.6, 0.0), 20.0,
                                25.0 * 2.5, 2.5);  // 143° on a 25 mm radius
  const std::vector<Silhouette> silhouettes = RenderSilhouettes(rig, axis, radius, {}, {}, 2);
  const SilhouetteRefiner refiner(rig, silhouettes);
  const SmoothingSpline spline = AxisSpline(axis);
  std::mt19937 rng(17);
  for (double s = 10.0; s < 75.0; s += 3.0) {
    const Refined r = RefineAt(refiner, spline, s, radius, false, rng);
    ASSERT_TRUE(r.fit.ok) << "s " << s;
    EXPECT_LT((r.fit.point - r.truth).norm(), 0.1) << "s " << s;
  }
}

TEST(SilhouetteRefinerTest, FindsTheCentreOfTheTipsCap) {
  const Rig rig = FixtureRig(3);
  std::mt19937 rng(18);
  for (int trial = 0; trial < 4; ++trial) {
    const double radius = Uniform(rng, 2.5, 4.0);
    const Polyline axis =
        ArcTube(rig.base_point, Vec3::UnitZ(), Vec3(1.0, Uniform(rng, -1, 1), 0.0), 30.0, 80.0,
                Uniform(rng, 0.3, 1.8));
    const std::vector<Silhouette> silhouettes =
        RenderSilhouettes(rig, axis, radius, {}, {}, 10 + trial);
    const SilhouetteRefiner refiner(rig, silhouettes);
    const Vec3 tip = axis.back();
    const Vec3 t = (axis.back() - axis[axis.size() - 9]).normalized();
    for (const double off : {-3.0, -1.0, 0.5, 2.0}) {
      const std::optional<double> lambda = refiner.FitTipOffset(tip + off * t, t, radius);
      ASSERT_TRUE(lambda.has_value());
      EXPECT_NEAR(*lambda, -off, 0.12) << "trial " << trial << " offset " << off;
    }
  }
}

TEST(SilhouetteRefinerTest, DropsAnEdgeThatDisagreesWithTheOthers) {
  const Rig rig = FixtureRig(3);
  const SilhouetteRefiner refiner(rig, {});
  std::mt19937 rng(19);
  const Vec3 p(1, 2, 3);
  const Vec3 t = Vec3(0.2, -0.3, 1.0).normalized();
  for (int trial = 0; trial < 20; ++trial) {
    Vec3 move(Uniform(rng, -1, 1), Uniform(rng, -1, 1), Uniform(rng, -1, 1));
    move -= move.dot(t) * t;
    const double radius = 3.0;
    std::vector<EdgeConstraint> edges;
    for (int k = 0; k < 6; ++k) {
      Vec3 n(Uniform(rng, -1, 1), Uniform(rng, -1, 1), Uniform(rng, -1, 1));
      n = (n - n.dot(t) * t).normalized();
      // What the edge measures: the distance that moving by `move` corrects.
      edges.push_back({n, radius - n.dot(move) + Uniform(rng, -0.01, 0.01)});
    }
    edges[static_cast<size_t>(trial % 6)].distance += trial % 2 ? 1.2 : -0.9;
    const AxisPointFit fit = refiner.FitAxisPoint(p, t, radius, false, edges);
    ASSERT_TRUE(fit.ok);
    EXPECT_EQ(fit.edges_used, 5);
    EXPECT_LT((fit.point - (p + move)).norm(), 0.03);
  }
}

TEST(SilhouetteRefinerTest, FailsWhenTheEdgesCannotFixThePoint) {
  const Rig rig = FixtureRig(3);
  const SilhouetteRefiner refiner(rig, {});
  const Vec3 t = Vec3::UnitZ();
  // Both edges of one camera: nearly opposite normals leave depth free.
  const std::vector<EdgeConstraint> one_view = {{Vec3(0.01, 1, 0).normalized(), 3.0},
                                                {Vec3(0.01, -1, 0).normalized(), 3.0}};
  EXPECT_FALSE(refiner.FitAxisPoint(Vec3::Zero(), t, 3.0, false, one_view).ok);
  EXPECT_FALSE(refiner.FitAxisPoint(Vec3::Zero(), t, 3.0, false, {}).ok);
  EXPECT_FALSE(refiner.FitTipOffset(Vec3::Zero(), t, 3.0).has_value());
}

}  // namespace
}  // namespace shapesense
