#include "libs/centerline/markers.h"

#include <gtest/gtest.h>

#include <random>

#include "libs/geometry/polyline.h"
#include "tests/libs/centerline/tube_fixture.h"

namespace shapesense {
namespace {

using testing::ArcTube;
using testing::FixtureGrid;
using testing::FixtureRig;
using testing::RenderSilhouettes;
using testing::Tape;
using testing::Uniform;
using testing::VoxelizeTube;

struct Scene {
  Rig rig;
  Polyline axis;
  double radius = 3.0;
  std::vector<Tape> tapes;
  VoxelCloud cloud;
};

Scene RandomScene(std::mt19937& rng) {
  Scene scene;
  scene.rig = FixtureRig(3);
  scene.radius = Uniform(rng, 2.5, 4.0);
  scene.axis = ArcTube(scene.rig.base_point, Vec3::UnitZ(), Vec3(Uniform(rng, -1, 1), 1, 0), 20.0,
                       Uniform(rng, 100.0, 150.0), Uniform(rng, 0.3, 2.4));
  for (double s = Uniform(rng, 15, 25); s < PolylineLength(scene.axis) - 15;
       s += Uniform(rng, 20, 35)) {
    scene.tapes.push_back({s, Uniform(rng, 3.0, 6.0)});
  }
  scene.cloud = VoxelizeTube(FixtureGrid(scene.rig), scene.axis, scene.radius, 0.5, scene.tapes);
  return scene;
}

std::vector<MarkerOnCurve> MarkersOf(const Scene& scene, int min_voxels) {
  const VoxelGraph graph(scene.cloud);
  const GeodesicBody body = FindGeodesicBody(scene.cloud, graph, scene.axis.front(), 15.0, 2.0);
  return FindMarkers(scene.cloud, graph, body, scene.axis, CumulativeArcLength(scene.axis),
                     min_voxels, 2.5);
}

TEST(FindMarkersTest, FindsEveryBandInOrderAtItsCentre) {
  std::mt19937 rng(21);
  for (int trial = 0; trial < 5; ++trial) {
    const Scene scene = RandomScene(rng);
    const std::vector<MarkerOnCurve> markers = MarkersOf(scene, 3);
    ASSERT_EQ(markers.size(), scene.tapes.size()) << "trial " << trial;
    const std::vector<double> arc = CumulativeArcLength(scene.axis);
    for (size_t m = 0; m < markers.size(); ++m) {
      EXPECT_NEAR(markers[m].arc_length, scene.tapes[m].center, 0.3) << "trial " << trial;
      EXPECT_LT(
          (markers[m].point - PointAtArcLength(scene.axis, arc, scene.tapes[m].center)).norm(),
          0.3);
      if (m > 0) {
        EXPECT_GT(markers[m].arc_length, markers[m - 1].arc_length);
      }
    }
  }
}

TEST(FindMarkersTest, IgnoresBandsOfTooFewVoxels) {
  std::mt19937 rng(22);
  const Scene scene = RandomScene(rng);
  const std::vector<MarkerOnCurve> all = MarkersOf(scene, 3);
  ASSERT_FALSE(all.empty());
  int smallest = all.front().voxels;
  for (const MarkerOnCurve& m : all) smallest = std::min(smallest, m.voxels);
  EXPECT_EQ(MarkersOf(scene, smallest + 1).size(), all.size() - 1);
  EXPECT_TRUE(MarkersOf(scene, 1000000).empty());
}

// Voxel labels carry the cameras' view-dependent shifts; the images give
// the band's centre back, whichever way the voxels erred.
TEST(LocateBandsInImagesTest, PullsMarkersBackToTheBandsCentres) {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 3; ++trial) {
    const Scene scene = RandomScene(rng);
    const std::vector<Silhouette> silhouettes =
        RenderSilhouettes(scene.rig, scene.axis, scene.radius, scene.tapes, {}, trial);
    const Polyline centerline = ResampleUniform(scene.axis, 1.0);
    const std::vector<double> arc = CumulativeArcLength(centerline);
    std::vector<MarkerOnCurve> markers;
    for (const Tape& tape : scene.tapes) {
      const double guess = tape.center + Uniform(rng, -2.5, 2.5);
      markers.push_back({guess, PointAtArcLength(centerline, arc, guess), 100});
    }
    LocateBandsInImages(scene.rig, silhouettes, centerline, arc, scene.radius, BandPrior{},
                        &markers);
    ASSERT_EQ(markers.size(), scene.tapes.size());
    for (size_t m = 0; m < markers.size(); ++m) {
      EXPECT_NEAR(markers[m].arc_length, scene.tapes[m].center, 0.2) << "trial " << trial;
      EXPECT_NEAR(markers[m].width, scene.tapes[m].width, 0.6) << "trial " << trial;
      EXPECT_GT(markers[m].std_mm, 0.0);
      EXPECT_LT(markers[m].std_mm, 0.2);
      EXPECT_GE(markers[m].views, 2);
      EXPECT_LT(
          (markers[m].point - PointAtArcLength(centerline, arc, markers[m].arc_length)).norm(),
          1e-9);
    }
  }
}

TEST(LocateBandsInImagesTest, ReportsBandsNoCameraSeesAsMissing) {
  std::mt19937 rng(24);
  const Scene scene = RandomScene(rng);
  // Silhouettes without tape: no camera sees a band.
  const std::vector<Silhouette> silhouettes =
      RenderSilhouettes(scene.rig, scene.axis, scene.radius, {}, {}, 0);
  const Polyline centerline = ResampleUniform(scene.axis, 1.0);
  const std::vector<double> arc = CumulativeArcLength(centerline);
  std::vector<MarkerOnCurve> markers = {{30.0, PointAtArcLength(centerline, arc, 30.0), 50},
                                        {60.0, PointAtArcLength(centerline, arc, 60.0), 50}};
  LocateBandsInImages(scene.rig, silhouettes, centerline, arc, scene.radius, BandPrior{}, &markers);
  EXPECT_TRUE(markers.empty());
}

}  // namespace
}  // namespace shapesense
