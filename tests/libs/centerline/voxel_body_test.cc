#include "libs/centerline/voxel_body.h"

#include "libs/centerline/block_geodesic.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <set>

#include "tests/libs/centerline/tube_fixture.h"

namespace shapesense {
namespace {

using testing::ArcTube;
using testing::FixtureGrid;
using testing::FixtureRig;
using testing::SpiralTube;
using testing::VoxelizeTube;

VoxelCloud RandomCloud(const VoxelGrid& grid, double fill, std::mt19937& rng) {
  VoxelCloud cloud;
  cloud.grid = grid;
  for (int64_t i = 0; i < grid.NumVoxels(); ++i) {
    if (testing::Uniform(rng, 0, 1) < fill) {
      cloud.voxels.push_back(static_cast<int32_t>(i));
      cloud.labels.push_back(kLabelBody);
    }
  }
  return cloud;
}

TEST(VoxelGraphTest, NeighboursMatchABruteForceSearch) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 5; ++trial) {
    VoxelGrid grid;
    grid.dims = {std::uniform_int_distribution<int>(1, 70)(rng),
                 std::uniform_int_distribution<int>(1, 9)(rng),
                 std::uniform_int_distribution<int>(1, 9)(rng)};
    const VoxelCloud cloud = RandomCloud(grid, testing::Uniform(rng, 0.1, 0.9), rng);
    const VoxelGraph graph(cloud);
    ASSERT_EQ(graph.size(), cloud.voxels.size());
    for (int32_t i = 0; i < static_cast<int32_t>(cloud.voxels.size()); ++i) {
      const std::array<int, 3> a = graph.coordinates(i);
      EXPECT_EQ(grid.Index(a[0], a[1], a[2]), cloud.voxels[static_cast<size_t>(i)]);
      std::set<std::pair<int32_t, int>> found;
      graph.ForEachNeighbor(i, [&](int32_t j, int differing) { found.insert({j, differing}); });
      std::set<std::pair<int32_t, int>> expected;
      for (int32_t j = 0; j < static_cast<int32_t>(cloud.voxels.size()); ++j) {
        const std::array<int, 3> b = graph.coordinates(j);
        const int dx = std::abs(a[0] - b[0]);
        const int dy = std::abs(a[1] - b[1]);
        const int dz = std::abs(a[2] - b[2]);
        if (j != i && dx <= 1 && dy <= 1 && dz <= 1) expected.insert({j, dx + dy + dz});
      }
      ASSERT_EQ(found, expected) << "voxel " << i << " of trial " << trial;
    }
  }
}

VoxelCloud CloudOf(const VoxelGrid& grid, const std::vector<std::array<int, 3>>& voxels) {
  VoxelCloud cloud;
  cloud.grid = grid;
  for (const auto& [x, y, z] : voxels)
    cloud.voxels.push_back(static_cast<int32_t>(grid.Index(x, y, z)));
  std::sort(cloud.voxels.begin(), cloud.voxels.end());
  cloud.labels.assign(cloud.voxels.size(), kLabelBody);
  return cloud;
}

TEST(GeodesicBodyTest, StepsAlongAnAxisAFaceDiagonalAndABodyDiagonal) {
  VoxelGrid grid;
  grid.voxel_size = 2.0;
  grid.dims = {21, 21, 21};
  // Three chains leave (10, 10, 10), far enough apart never to touch.
  std::vector<std::array<int, 3>> voxels = {{10, 10, 10}};
  for (int k = 1; k <= 8; ++k) {
    voxels.push_back({10 + k, 10, 10});
    voxels.push_back({10 - k, 10 + k, 10});
    voxels.push_back({10 - k, 10 - k, 10 - k});
  }
  const VoxelCloud cloud = CloudOf(grid, voxels);
  const VoxelGraph graph(cloud);
  const GeodesicBody body = FindGeodesicBody(cloud, graph, grid.Center(10, 10, 10), 1.0, 0.0);
  ASSERT_TRUE(body.error.empty()) << body.error;
  ASSERT_EQ(body.members.size(), cloud.voxels.size());
  ASSERT_EQ(body.seeds.size(), 1u);
  for (int32_t i = 0; i < static_cast<int32_t>(cloud.voxels.size()); ++i) {
    const auto [x, y, z] = graph.coordinates(i);
    const int k = std::abs(x - 10);
    const int axes_moved = (x != 10) + (y != 10) + (z != 10);
    EXPECT_NEAR(body.distance[static_cast<size_t>(i)], 2.0 * k * std::sqrt(axes_moved), 1e-4)
        << x << " " << y << " " << z;
  }
  for (size_t m = 1; m < body.members.size(); ++m) {
    EXPECT_LE(body.distance[static_cast<size_t>(body.members[m - 1])],
              body.distance[static_cast<size_t>(body.members[m])]);
  }
}

TEST(GeodesicBodyTest, IgnoresOtherComponentsAndFailsWithoutABase) {
  const Rig rig = FixtureRig(3);
  const VoxelGrid grid = FixtureGrid(rig);
  VoxelCloud cloud = VoxelizeTube(
      grid, ArcTube(rig.base_point, Vec3::UnitZ(), Vec3::UnitX(), 20, 60, 1.0), 3.0, 0.5);
  const size_t tube_voxels = cloud.voxels.size();
  // A blob floating beside the tube.
  const VoxelCloud blob = VoxelizeTube(grid, {Vec3(-60, -60, 0), Vec3(-60, -60, 20)}, 4.0, 0.0);
  cloud.voxels.insert(cloud.voxels.end(), blob.voxels.begin(), blob.voxels.end());
  std::sort(cloud.voxels.begin(), cloud.voxels.end());
  cloud.labels.assign(cloud.voxels.size(), kLabelBody);
  const VoxelGraph graph(cloud);
  const GeodesicBody body = FindGeodesicBody(cloud, graph, rig.base_point, 15.0, 2.0);
  ASSERT_TRUE(body.error.empty());
  EXPECT_EQ(body.members.size(), tube_voxels);
  for (const int32_t i : body.members) {
    EXPECT_GT((VoxelCenter(grid, graph.coordinates(i)) - Vec3(-60, -60, 10)).norm(), 20.0);
  }
  const GeodesicBody none = FindGeodesicBody(cloud, graph, Vec3(90, 90, 90), 15.0, 2.0);
  EXPECT_FALSE(none.error.empty());
  EXPECT_TRUE(none.members.empty());
}

// The arc length along `truth` of each slice centroid.
std::vector<double> ArcOfSlices(const std::vector<BodySlice>& slices, const Polyline& truth) {
  const std::vector<double> arc = CumulativeArcLength(truth);
  std::vector<double> out;
  for (const BodySlice& slice : slices) {
    out.push_back(ClosestPointOnPolyline(truth, arc, slice.centroid).arc_length);
  }
  return out;
}

// The reference orders the voxels by their angle about a fixed centre
// (here about a vertical axis through it); angles repeat once the body turns
// by more than a full turn about it, and no sort can order them.
std::vector<double> AngleSortArcs(const VoxelCloud& cloud, const VoxelGraph& graph,
                                  const Polyline& truth, const Vec3& center) {
  std::vector<std::pair<double, int32_t>> by_angle;
  for (int32_t i = 0; i < static_cast<int32_t>(cloud.voxels.size()); ++i) {
    const Vec3 d = VoxelCenter(cloud.grid, graph.coordinates(i)) - center;
    by_angle.emplace_back(std::atan2(d.y(), d.x()), i);
  }
  std::sort(by_angle.begin(), by_angle.end());
  const std::vector<double> arc = CumulativeArcLength(truth);
  std::vector<double> out;
  for (const auto& [angle, i] : by_angle) {
    out.push_back(ClosestPointOnPolyline(truth, arc, VoxelCenter(cloud.grid, graph.coordinates(i)))
                      .arc_length);
  }
  return out;
}

// Largest step back along the truth between consecutive entries, mm.
double WorstStepBack(const std::vector<double>& arcs) {
  double worst = 0.0;
  double furthest = arcs.empty() ? 0.0 : arcs.front();
  for (const double s : arcs) {
    worst = std::max(worst, furthest - s);
    furthest = std::max(furthest, s);
  }
  return worst;
}

using GeodesicSearch = GeodesicBody (*)(const VoxelCloud&, const VoxelGraph&, const Vec3&, double,
                                        double);

void ExpectOrderedAlong(const Polyline& truth, double radius, GeodesicSearch search) {
  const Rig rig = FixtureRig(3);
  const VoxelGrid grid = FixtureGrid(rig);
  const VoxelCloud cloud = VoxelizeTube(grid, truth, radius, 0.5);
  const VoxelGraph graph(cloud);
  const GeodesicBody body = search(cloud, graph, truth.front(), 15.0, 2.0);
  ASSERT_TRUE(body.error.empty());
  EXPECT_EQ(body.members.size(), cloud.voxels.size());
  const std::vector<BodySlice> slices = SliceByDistance(cloud, graph, body, 1.0);
  const std::vector<double> arcs = ArcOfSlices(slices, truth);
  ASSERT_GT(arcs.size(), 50u);
  // Slices run base → tip without stepping back, cover the body, and their
  // centroids lie on the axis.
  EXPECT_LT(WorstStepBack(arcs), 0.5);
  EXPECT_LT(arcs.front(), 2.0);
  EXPECT_GT(arcs.back(), PolylineLength(truth) - 2.0);
  const std::vector<double> arc = CumulativeArcLength(truth);
  for (const BodySlice& slice : slices) {
    const ClosestPoint closest = ClosestPointOnPolyline(truth, arc, slice.centroid);
    if (closest.arc_length > 3.0 * radius && closest.arc_length < arc.back() - 3.0 * radius) {
      EXPECT_LT(closest.distance, 0.6);
    }
  }
}

TEST(GeodesicBodyTest, OrdersAUTurnOf200Degrees) {
  const Rig rig = FixtureRig(3);
  const Polyline truth = ArcTube(rig.base_point, Vec3::UnitZ(), Vec3::UnitX(), 40.0,
                                 40.0 * 200.0 / 180.0 * 3.1416, 200.0 * std::numbers::pi / 180.0);
  ExpectOrderedAlong(truth, 3.0, FindGeodesicBody);
  ExpectOrderedAlong(truth, 3.0, FindGeodesicBodyByBlocks);
}

TEST(GeodesicBodyTest, OrdersASpiralOfOneAndAHalfTurns) {
  const Rig rig = FixtureRig(3);
  Vec3 axis_point;
  const Polyline truth = SpiralTube(rig.base_point, 20.0, 15.0, 66.0, 1.5, &axis_point);
  ExpectOrderedAlong(truth, 2.5, FindGeodesicBody);
  ExpectOrderedAlong(truth, 2.5, FindGeodesicBodyByBlocks);
  // Whereas the angle about the spiral's axis puts its turns on top of
  // each other.
  const VoxelCloud cloud = VoxelizeTube(FixtureGrid(rig), truth, 2.5, 0.5);
  const VoxelGraph graph(cloud);
  EXPECT_GT(WorstStepBack(AngleSortArcs(cloud, graph, truth, axis_point)), 50.0);
}

// The search on 2×2×2 blocks gives every voxel nearly the distance of the
// search on voxels, and orders the body the same way to within a voxel.
TEST(GeodesicBodyTest, BlocksGiveTheDistancesOfVoxels) {
  const Rig rig = FixtureRig(3);
  std::mt19937 rng(4);
  for (int trial = 0; trial < 4; ++trial) {
    const Polyline truth = ArcTube(rig.base_point, Vec3(testing::Uniform(rng, -0.3, 0.3), 0.2, 1.0),
                                   Vec3(1, testing::Uniform(rng, -1, 1), 0), 20.0,
                                   testing::Uniform(rng, 60, 140), testing::Uniform(rng, 0.5, 3.5));
    const VoxelCloud cloud =
        VoxelizeTube(FixtureGrid(rig), truth, testing::Uniform(rng, 1.5, 4.0), 0.5);
    const VoxelGraph graph(cloud);
    const GeodesicBody exact = FindGeodesicBody(cloud, graph, truth.front(), 15.0, 2.0);
    const GeodesicBody blocks = FindGeodesicBodyByBlocks(cloud, graph, truth.front(), 15.0, 2.0);
    ASSERT_TRUE(blocks.error.empty());
    ASSERT_EQ(blocks.members.size(), exact.members.size());
    EXPECT_FALSE(blocks.seeds.empty());
    double sum_sq = 0.0;
    for (size_t i = 0; i < cloud.voxels.size(); ++i) {
      const double difference = blocks.distance[i] - exact.distance[i];
      sum_sq += difference * difference;
      // The two differ most near the base, where the blocks' seeds are
      // coarser, and by a few per cent of the length (both are chamfer
      // approximations of the true geodesic, at different scales).
      EXPECT_LT(std::abs(difference), 1.5 + 0.03 * exact.distance[i]) << "trial " << trial;
    }
    EXPECT_LT(std::sqrt(sum_sq / static_cast<double>(cloud.voxels.size())), 0.8);
    for (size_t m = 1; m < blocks.members.size(); ++m) {
      EXPECT_LT(blocks.distance[static_cast<size_t>(blocks.members[m - 1])],
                blocks.distance[static_cast<size_t>(blocks.members[m])] + 1.0);
    }
  }
}

}  // namespace
}  // namespace shapesense
