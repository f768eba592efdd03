#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "libs/geometry/polyline.h"
#include "libs/sim/scene_generators.h"
#include "tests/libs/sim/sim_test_util.h"

namespace shapesense {
namespace {

TEST(MakeSyntheticRigTest, CamerasSurroundTheWorkspaceAndSeeItsCentreNearTheImageCentre) {
  for (uint32_t seed = 0; seed < 10; ++seed) {
    SyntheticRigOptions options;
    options.seed = seed;
    options.num_cameras = 3 + static_cast<int>(seed % 3);
    const Rig rig = MakeSyntheticRig(options);
    ASSERT_EQ(rig.Validate(), "");
    ASSERT_EQ(rig.cameras.size(), static_cast<size_t>(options.num_cameras));
    EXPECT_TRUE(rig.workspace_max.isApprox(Vec3::Constant(options.workspace_half_size)));
    EXPECT_TRUE(rig.base_point.isApprox(Vec3(0, 0, -options.workspace_half_size)));
    Vec3 mean_direction = Vec3::Zero();
    for (const Camera& camera : rig.cameras) {
      const Vec3 center = camera.Center();
      EXPECT_NEAR(center.norm(), options.distance, 0.101 * options.distance);
      mean_direction += center.normalized() / options.num_cameras;
      // Aim within ±2° (plus roll) and principal point within ±8 px.
      const auto pixel = camera.Project(Vec3::Zero());
      ASSERT_TRUE(pixel.has_value());
      const Vec2 image_center(0.5 * (camera.width - 1), 0.5 * (camera.height - 1));
      const double limit = camera.camera_matrix(0, 0) * std::tan(2.9 * std::numbers::pi / 180) + 12;
      EXPECT_LT((*pixel - image_center).norm(), limit) << camera.name;
      // x right, y down: the vertical axis goes up in the image.
      const auto above = camera.Project(Vec3(0, 0, 50));
      EXPECT_LT(above->y(), pixel->y() - 50);
      EXPECT_NEAR(above->x(), pixel->x(), 15);
    }
    // Spread evenly around z: the horizontal directions cancel out.
    EXPECT_LT(mean_direction.head<2>().norm(), 0.15);
  }
}

TEST(MakeSyntheticRigTest, SeedDecidesTheJitterAndDistortionCanBeOff) {
  SyntheticRigOptions options;
  options.seed = 4;
  const Rig first = MakeSyntheticRig(options);
  const Rig again = MakeSyntheticRig(options);
  options.seed = 5;
  const Rig other = MakeSyntheticRig(options);
  options.seed = 4;
  options.distortion = false;
  const Rig undistorted = MakeSyntheticRig(options);
  for (size_t i = 0; i < first.cameras.size(); ++i) {
    EXPECT_TRUE(first.cameras[i].cam_from_world.isApprox(again.cameras[i].cam_from_world, 0.0));
    EXPECT_EQ(first.cameras[i].distortion, again.cameras[i].distortion);
    EXPECT_FALSE(first.cameras[i].cam_from_world.isApprox(other.cameras[i].cam_from_world, 1e-6));
    EXPECT_NE(first.cameras[i].distortion, other.cameras[i].distortion);
    EXPECT_TRUE(first.cameras[i].camera_matrix.isApprox(undistorted.cameras[i].camera_matrix));
    for (const double c : undistorted.cameras[i].distortion) EXPECT_EQ(c, 0.0);
    const auto& k = first.cameras[i].distortion;
    EXPECT_TRUE(k[0] >= -0.15 && k[0] <= 0.05);
    EXPECT_LE(std::abs(k[2]), 2e-3);
    EXPECT_LE(std::abs(k[3]), 2e-3);
  }
}

TEST(MakeSyntheticRigTest, RejectsInvalidOptions) {
  EXPECT_EQ(SyntheticRigOptions{}.Validate(), "");
  SyntheticRigOptions options;
  options.num_cameras = 0;
  EXPECT_NE(options.Validate().find("num_cameras"), std::string::npos);
  EXPECT_THROW(MakeSyntheticRig(options), std::invalid_argument);
  options = {};
  options.distance = 100.0;  // inside the workspace
  EXPECT_NE(options.Validate().find("distance"), std::string::npos);
  options = {};
  options.focal_px = -1.0;
  EXPECT_NE(options.Validate().find("focal_px"), std::string::npos);
}

// Every check RandomScene promises, for one scene.
void ExpectSceneGuarantees(const Rig& rig, const TubeScene& scene, int num_tapes) {
  const std::vector<double> arc = CumulativeArcLength(scene.centerline);
  const double length = arc.back();
  EXPECT_GE(length, 120.0 - 0.01);
  EXPECT_LE(length, 200.0);
  EXPECT_GE(scene.radius, 2.5);
  EXPECT_LE(scene.radius, 4.0);
  EXPECT_TRUE(scene.centerline.front().isApprox(rig.base_point));
  // Inside the workspace by 5 mm, except where it enters through the bottom.
  for (size_t i = 0; i < scene.centerline.size(); ++i) {
    const Vec3& p = scene.centerline[i];
    const Vec3 low = rig.workspace_min.array() + 5.0 + scene.radius;
    const Vec3 high = rig.workspace_max.array() - 5.0 - scene.radius;
    EXPECT_TRUE(p.x() >= low.x() && p.y() >= low.y() && p.x() <= high.x() && p.y() <= high.y());
    EXPECT_LE(p.z(), high.z());
    EXPECT_GE(p.z(), rig.workspace_min.z() + (arc[i] > 10.0 + 2 * scene.radius ? 5.0 : 0.0));
  }
  // Tapes: in the middle of the body, 3-6 mm wide, ordered, not overlapping.
  ASSERT_EQ(scene.tapes.size(), static_cast<size_t>(num_tapes));
  for (size_t k = 0; k < scene.tapes.size(); ++k) {
    const TapeBand& tape = scene.tapes[k];
    EXPECT_GE(tape.width, 3.0);
    EXPECT_LE(tape.width, 6.0);
    EXPECT_GE(tape.center_arc_length - tape.width / 2, 0.05 * length);
    EXPECT_LE(tape.center_arc_length + tape.width / 2, 0.95 * length);
    if (k > 0) {
      const TapeBand& previous = scene.tapes[k - 1];
      EXPECT_GT(tape.center_arc_length - tape.width / 2,
                previous.center_arc_length + previous.width / 2);
    }
  }
  // The surface projects at least 8 px inside every image.
  for (const Camera& camera : rig.cameras) {
    for (double s = 0.0; s <= length; s += 2.0) {
      const Vec3 center = PointAtArcLength(scene.centerline, arc, s);
      const Vec3 tangent = testing::TangentAt(scene.centerline, arc, s);
      for (int k = 0; k < 8; ++k) {
        const Vec3 p = center + scene.radius * testing::PerpendicularAt(tangent, k * 0.785);
        const auto pixel = camera.Project(p);
        ASSERT_TRUE(pixel.has_value());
        EXPECT_TRUE(pixel->x() >= 8 && pixel->y() >= 8 && pixel->x() <= camera.width - 9 &&
                    pixel->y() <= camera.height - 9)
            << camera.name << " s " << s << " at " << pixel->transpose();
      }
    }
  }
  // Parts far apart along the tube stay more than three radii apart (surface to surface).
  const Polyline coarse = ResampleUniform(scene.centerline, 1.0);
  for (size_t i = 0; i < coarse.size(); ++i) {
    for (size_t j = i + 40; j < coarse.size(); ++j) {
      EXPECT_GE((coarse[i] - coarse[j]).norm(), 5.0 * scene.radius - 1e-9);
    }
  }
}

TEST(RandomSceneTest, KeepsItsGuaranteesOverManySeeds) {
  SyntheticRigOptions options;
  options.seed = 2;
  const Rig rig = MakeSyntheticRig(options);
  int s_curves = 0;
  for (uint32_t seed = 0; seed < 20; ++seed) {
    const int num_tapes = 1 + static_cast<int>(seed % 5);
    const double max_bend = seed < 10 ? 1.6 : std::numbers::pi;
    const TubeScene scene = RandomScene(rig, seed, max_bend, num_tapes);
    SCOPED_TRACE("seed " + std::to_string(seed));
    ExpectSceneGuarantees(rig, scene, num_tapes);
    // Total turning is at most the bend (arc) or twice it (S-curve).
    const Vec3 start = (scene.centerline[1] - scene.centerline[0]).normalized();
    const Vec3 end =
        (scene.centerline.back() - scene.centerline[scene.centerline.size() - 2]).normalized();
    EXPECT_LE(std::acos(std::clamp(start.dot(end), -1.0, 1.0)), max_bend + 0.01);
    // An S-curve bends the other way in its second half.
    const double length = PolylineLength(scene.centerline);
    const std::vector<double> arc = CumulativeArcLength(scene.centerline);
    const auto bending = [&](double s) -> Vec3 {
      return testing::TangentAt(scene.centerline, arc, s + 2.0) -
             testing::TangentAt(scene.centerline, arc, s - 2.0);
    };
    if (bending(0.25 * length).dot(bending(0.75 * length)) < -1e-6) ++s_curves;
  }
  EXPECT_GE(s_curves, 4) << "about half the scenes should be S-curves";
  EXPECT_LE(s_curves, 16) << "about half the scenes should be arcs";
}

TEST(RandomSceneTest, IsDeterministicPerSeedAndStraightWithoutBend) {
  const Rig rig = MakeSyntheticRig({});
  const TubeScene a = RandomScene(rig, 9, 1.0);
  const TubeScene b = RandomScene(rig, 9, 1.0);
  const TubeScene c = RandomScene(rig, 10, 1.0);
  ASSERT_EQ(a.centerline.size(), b.centerline.size());
  for (size_t i = 0; i < a.centerline.size(); ++i) EXPECT_EQ(a.centerline[i], b.centerline[i]);
  EXPECT_NE(a.radius, c.radius);
  const TubeScene straight = RandomScene(rig, 3, 0.0);
  const Vec3 tip = straight.centerline.back();
  EXPECT_NEAR(tip.x(), rig.base_point.x(), 1e-9);
  EXPECT_NEAR(tip.y(), rig.base_point.y(), 1e-9);
}

TEST(RandomSceneTest, RejectsARigTooSmallForAnyTube) {
  SyntheticRigOptions options;
  options.workspace_half_size = 50.0;
  EXPECT_THROW(RandomScene(MakeSyntheticRig(options), 1, 1.0), std::invalid_argument);
}

TEST(TruthOfTest, MarkersSitOnTheCentrelineAtTheTapeCentres) {
  const Rig rig = MakeSyntheticRig({});
  for (uint32_t seed = 0; seed < 5; ++seed) {
    const TubeScene scene = RandomScene(rig, seed, 1.2, 4);
    const GroundTruth truth = TruthOf(scene);
    const std::vector<double> arc = CumulativeArcLength(scene.centerline);
    EXPECT_EQ(truth.centerline.size(), scene.centerline.size());
    EXPECT_EQ(truth.tip, scene.centerline.back());
    EXPECT_DOUBLE_EQ(truth.length, arc.back());
    ASSERT_EQ(truth.markers.size(), scene.tapes.size());
    ASSERT_EQ(truth.marker_arc_length.size(), scene.tapes.size());
    for (size_t k = 0; k < scene.tapes.size(); ++k) {
      EXPECT_EQ(truth.marker_arc_length[k], scene.tapes[k].center_arc_length);
      const ClosestPoint closest = ClosestPointOnPolyline(scene.centerline, arc, truth.markers[k]);
      EXPECT_LT(closest.distance, 1e-9);
      EXPECT_NEAR(closest.arc_length, scene.tapes[k].center_arc_length, 1e-6);
    }
  }
}

}  // namespace
}  // namespace shapesense
