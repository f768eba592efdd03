// The scripted trajectory: keyframes reproduced exactly (against libs/sim's
// own arc and S-curve generators), looping, continuous, inside the cameras.

#include "libs/sim/trajectory.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "libs/sim/scene_generators.h"
#include "runtime/config_file.h"

namespace shapesense {
namespace {

double MaxDistance(const Polyline& a, const Polyline& b) {
  if (a.size() != b.size()) return INFINITY;
  double worst = 0.0;
  for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a[i] - b[i]).norm());
  return worst;
}

TrajectoryOptions TwoKeyframes() {
  TrajectoryOptions options;
  options.keyframes = {{0.0, "arc", 150.0, 1.2, 0.4, 0.0}, {1.0, "s_curve", 170.0, 0.7, -0.5, 0.4}};
  options.loop_period = 2.5;
  return options;
}

Rig TestRig() { return MakeSyntheticRig(SyntheticRigOptions{}); }

TEST(Trajectory, KeyframesAreTheArcsAndSCurvesOfLibsSim) {
  const TrajectoryOptions options = TwoKeyframes();
  const Rig rig = TestRig();
  const TubeScene arc = SceneAt(options, rig, 0.0);
  const Vec3 arc_plane(std::cos(0.4), std::sin(0.4), 0.0);
  EXPECT_LT(MaxDistance(arc.centerline,
                        ArcCenterline(rig.base_point, Vec3::UnitZ(), arc_plane, 0.0, 150.0, 1.2)),
            1e-9);
  const TubeScene s_curve = SceneAt(options, rig, 1.0);
  const Vec3 s_plane(std::cos(-0.5), std::sin(-0.5), 0.0);
  EXPECT_LT(MaxDistance(s_curve.centerline,
                        SCurveCenterline(rig.base_point, Vec3::UnitZ(), s_plane, 85.0, 0.7, 0.4)),
            1e-9);
  EXPECT_EQ(arc.radius, options.tube_radius);
  EXPECT_EQ(arc.lead_in_length, options.lead_in_length);
}

TEST(Trajectory, RepeatsEveryLoopPeriod) {
  const TrajectoryOptions options = TwoKeyframes();
  const Rig rig = TestRig();
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> time(-10.0, 10.0);
  for (int trial = 0; trial < 20; ++trial) {
    const double t = time(rng);
    EXPECT_LT(MaxDistance(SceneAt(options, rig, t).centerline,
                          SceneAt(options, rig, t + 3 * options.loop_period).centerline),
              1e-6)
        << "t = " << t;
  }
}

// No jumps: between keyframes, across them, and where the loop closes.
TEST(Trajectory, MovesContinuously) {
  const TrajectoryOptions options = TwoKeyframes();
  const Rig rig = TestRig();
  const double dt = 1e-4;
  for (double t = -0.01; t < 2 * options.loop_period; t += 0.0371) {
    const TubeScene a = SceneAt(options, rig, t);
    const TubeScene b = SceneAt(options, rig, t + dt);
    EXPECT_LT((a.centerline.back() - b.centerline.back()).norm(), 0.1) << "tip jumps at t = " << t;
  }
}

// Every in-between shape is two circular pieces: curvature constant on each
// half, and the sampled length is the pose's.
TEST(Trajectory, InBetweenShapesHaveTheirPosesLengthAndCurvature) {
  const TrajectoryOptions options = TwoKeyframes();
  const Rig rig = TestRig();
  for (const double t : {0.25, 0.5, 0.77, 1.6, 2.2}) {
    const TrajectoryPose pose = PoseAt(options, t);
    const TubeScene scene = SceneOf(options, rig, pose);
    const GroundTruth truth = TruthOf(scene);
    EXPECT_NEAR(truth.length, pose.length, 1e-3 * pose.length) << t;
    // Turning angle over a sample step = curvature x step.
    const Polyline& c = scene.centerline;
    for (size_t i = 1; i + 1 < c.size(); i += 37) {
      const Vec3 u = (c[i] - c[i - 1]).normalized();
      const Vec3 v = (c[i + 1] - c[i]).normalized();
      const double step = (c[i + 1] - c[i]).norm();
      const double s = pose.length * static_cast<double>(i) / static_cast<double>(c.size() - 1);
      if (std::abs(s - pose.length / 2) < 1.0) continue;  // the joint
      EXPECT_NEAR(std::acos(std::clamp(u.dot(v), -1.0, 1.0)) / step, CurvatureAt(pose, s), 2e-4)
          << "t " << t << " s " << s;
    }
    ASSERT_EQ(scene.tapes.size(), options.tapes.size());
    EXPECT_NEAR(scene.tapes[0].center_arc_length, options.tapes[0].position * pose.length, 1e-9);
  }
}

TEST(Trajectory, DefaultMotionStaysInsideEveryCamera) {
  const TrajectoryOptions options;
  ASSERT_EQ(options.Validate(), "");
  const Rig rig = TestRig();
  for (double t = 0.0; t < options.loop_period; t += 0.25) {
    const TubeScene scene = SceneAt(options, rig, t);
    for (const Camera& camera : rig.cameras) {
      for (size_t i = 0; i < scene.centerline.size(); i += 20) {
        const std::optional<Vec2> pixel = camera.Project(scene.centerline[i]);
        ASSERT_TRUE(pixel && camera.InImage(*pixel)) << camera.name << " at t = " << t;
      }
    }
  }
}

TEST(Trajectory, ValidateNamesTheBadKey) {
  TrajectoryOptions options = TwoKeyframes();
  options.keyframes[1].time = 0.0;
  EXPECT_NE(options.Validate().find("keyframes[1].time"), std::string::npos) << options.Validate();
  options = TwoKeyframes();
  options.keyframes[0].shape = "helix";
  EXPECT_NE(options.Validate().find("keyframes[0].shape"), std::string::npos);
  options = TwoKeyframes();
  options.loop_period = 1.0;
  EXPECT_NE(options.Validate().find("loop_period"), std::string::npos);
  options = TwoKeyframes();
  options.keyframes[0].length = 5.0;
  EXPECT_NE(options.Validate().find("keyframes[0].length"), std::string::npos);
  options = TrajectoryOptions{};
  options.loop_period = 5.0;
  EXPECT_NE(options.Validate().find("loop_period"), std::string::npos) << "the defaults end at 6 s";
  options = TwoKeyframes();
  options.tapes[2].position = 1.5;
  EXPECT_NE(options.Validate().find("tapes[2].position"), std::string::npos);
}

// Bands that cannot all lie apart on the tube are refused by name, before
// anything is drawn or measured.
TEST(Trajectory, RefusesBandsTheTubeCannotCarry) {
  TrajectoryOptions options = TwoKeyframes();
  ASSERT_EQ(options.Validate(), "");
  // Wider than the spacing between them: 30 mm apart, 32 mm of half-widths.
  options.tapes = {{0.2, 4.0}, {0.4, 60.0}};
  EXPECT_NE(options.Validate().find("wider than the spacing between them"), std::string::npos)
      << options.Validate();
  EXPECT_NE(options.Validate().find("tapes[1]"), std::string::npos);
  // More bands than the tube carries.
  options.tapes.clear();
  for (int i = 0; i < 50; ++i) options.tapes.push_back({0.02 * i, 5.0});
  EXPECT_NE(options.Validate().find("more bands than the tube can carry"), std::string::npos)
      << options.Validate();
  // A band off the tube's end, on the shortest keyframe.
  options.tapes = {{0.99, 8.0}};
  EXPECT_NE(options.Validate().find("runs off"), std::string::npos) << options.Validate();
  // Out of order.
  options.tapes = {{0.6, 4.0}, {0.3, 4.0}};
  EXPECT_NE(options.Validate().find("tapes[1]"), std::string::npos) << options.Validate();
}

// A keyframe given in a file takes TrajectoryKeyframe's defaults for what it
// leaves out, whatever the built-in keyframes are.
TEST(Trajectory, KeyframesOfAFileStartFromTheKeyframeDefaults) {
  const auto options = OptionsFromYamlText<TrajectoryOptions>(
      "keyframes:\n"
      "  - {time: 0.0, bend_angle: 0.5}\n"
      "  - {time: 1.0}\n"
      "  - {time: 2.0, shape: s_curve}\n"
      "loop_period: 3.0\n",
      "test");
  ASSERT_EQ(options.keyframes.size(), 3u);
  const TrajectoryKeyframe defaults;
  EXPECT_EQ(options.keyframes[1].bend_angle, defaults.bend_angle);
  EXPECT_EQ(options.keyframes[2].twist, defaults.twist);
  EXPECT_EQ(options.keyframes[2].bend_plane, defaults.bend_plane);
  EXPECT_EQ(options.keyframes[2].length, defaults.length);
}

TEST(Trajectory, TheDefaultsAreTheShippedConfig) {
  const auto shipped = LoadOptionsFile<TrajectoryOptions>(std::string(SHAPESENSE_SOURCE_DIR) +
                                                          "/config/rig_sim.yaml");
  const Rig rig = TestRig();
  for (const double t : {0.0, 1.3, 3.9, 5.5, 7.7}) {
    EXPECT_LT(MaxDistance(SceneAt(shipped, rig, t).centerline,
                          SceneAt(TrajectoryOptions{}, rig, t).centerline),
              1e-9)
        << t;
  }
}

TEST(Trajectory, TheShippedConfigLoadsAndRoundTrips) {
  const auto options = LoadOptionsFile<TrajectoryOptions>(std::string(SHAPESENSE_SOURCE_DIR) +
                                                          "/config/rig_sim.yaml");
  EXPECT_EQ(options.Validate(), "");
  const auto again = OptionsFromYaml<TrajectoryOptions>(OptionsToYaml(options), "round trip");
  ASSERT_EQ(again.keyframes.size(), options.keyframes.size());
  for (size_t i = 0; i < options.keyframes.size(); ++i) {
    EXPECT_EQ(again.keyframes[i].shape, options.keyframes[i].shape);
    EXPECT_EQ(again.keyframes[i].bend_angle, options.keyframes[i].bend_angle);
  }
  EXPECT_EQ(again.loop_period, options.loop_period);
}

}  // namespace
}  // namespace shapesense
