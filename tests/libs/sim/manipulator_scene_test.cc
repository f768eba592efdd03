// The scene of a configuration: its centreline is the model's, moved into
// the world; the bands sit where the layout puts them on the compressed
// sections; the truth carries q; and sensing q on the exact truth gives it
// back (the scene and the sensing agree on the layout).
#include "libs/sim/manipulator_scene.h"

#include <gtest/gtest.h>

#include <numbers>
#include <random>
#include <stdexcept>

#include "libs/geometry/polyline.h"
#include "libs/mechanics/configuration_geometry.h"
#include "libs/mechanics/configuration_sensing.h"

namespace shapesense {
namespace {

constexpr SectionLengths kRest{60.0, 140.0};

Pose3 RandomPose(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Pose3 pose = Pose3::Identity();
  pose.linear() = Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized())
                      .toRotationMatrix();
  pose.translation() = 100.0 * Vec3(u(rng), u(rng), u(rng));
  return pose;
}

// Bends up to 120 degrees in any plane, strains 0-3%.
Configuration RandomConfiguration(std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double kappa = 2.0 * std::numbers::pi / 3.0 * unit(rng) / kRest.distal;
  const double phi = 2.0 * std::numbers::pi * unit(rng);
  return {kappa * std::sin(phi), -kappa * std::cos(phi), 0.03 * unit(rng), 0.03 * unit(rng)};
}

ManipulatorSceneOptions ThreeBands() {
  ManipulatorSceneOptions options;
  options.tapes.proximal_band_before_junction = 25.0;
  return options;
}

class ManipulatorSceneTest : public ::testing::Test {
 protected:
  std::mt19937 rng_{77};
};

TEST_F(ManipulatorSceneTest, CenterlineIsTheModelsInTheWorldAndTheTruthCarriesQ) {
  for (int trial = 0; trial < 10; ++trial) {
    const Configuration q = RandomConfiguration(rng_);
    const Pose3 world_from_base = RandomPose(rng_);
    const TubeScene scene = SceneOfConfiguration(q, kRest, world_from_base, {});
    const GroundTruth truth = TruthOf(scene);
    ASSERT_TRUE(truth.configuration.has_value());
    EXPECT_EQ(*truth.configuration, q);
    EXPECT_LT((scene.centerline.front() - world_from_base.translation()).norm(), 1e-9);
    EXPECT_LT((truth.tip - world_from_base * BaseFromTip(q, kRest).translation()).norm(), 1e-9);
    const SectionLengths compressed = CompressedLengths(q, kRest);
    EXPECT_NEAR(truth.length, compressed.proximal + compressed.distal, 1e-3);
    for (size_t i = 1; i < scene.centerline.size(); ++i) {
      EXPECT_LE((scene.centerline[i] - scene.centerline[i - 1]).norm(), 0.25 + 1e-9);
    }
  }
}

TEST_F(ManipulatorSceneTest, BandsSitOnTheCompressedSections) {
  for (int trial = 0; trial < 10; ++trial) {
    const Configuration q = RandomConfiguration(rng_);
    const Pose3 world_from_base = RandomPose(rng_);
    const ManipulatorSceneOptions options = ThreeBands();
    const GroundTruth truth = TruthOf(SceneOfConfiguration(q, kRest, world_from_base, options));
    ASSERT_EQ(truth.markers.size(), 3u);
    const SectionLengths compressed = CompressedLengths(q, kRest);
    const Vec3 proximal(0.0, (kRest.proximal - 25.0) * (1.0 - q(kStrainProximal)), 0.0);
    const Vec3 distal =
        BaseFromDistalPoint(q, kRest, compressed.distal - 10.0 * (1.0 - q(kStrainDistal)))
            .translation();
    // Markers on the 0.25 mm polyline: within its sagitta of the arc.
    EXPECT_LT((truth.markers[0] - world_from_base * proximal).norm(), 1e-6);
    EXPECT_LT((truth.markers[1] - world_from_base * Vec3(0.0, compressed.proximal, 0.0)).norm(),
              1e-6);
    EXPECT_LT((truth.markers[2] - world_from_base * distal).norm(), 1e-4);
  }
}

TEST_F(ManipulatorSceneTest, ABodyThatStartsPastTheBaseDropsTheBandsBeforeIt) {
  const Configuration q(0.005, -0.002, 0.02, 0.01);
  const Pose3 world_from_base = RandomPose(rng_);
  ManipulatorSceneOptions options = ThreeBands();
  options.body_start = 40.0;  // past the proximal band, 35 * 0.98 mm from the base
  const TubeScene scene = SceneOfConfiguration(q, kRest, world_from_base, options);
  EXPECT_LT((scene.centerline.front() - world_from_base * Vec3(0.0, 40.0, 0.0)).norm(), 1e-9);
  const GroundTruth truth = TruthOf(scene);
  ASSERT_EQ(truth.markers.size(), 2u);
  EXPECT_NEAR(truth.marker_arc_length[0], 60.0 * 0.98 - 40.0, 1e-9);
  EXPECT_LT((truth.tip - world_from_base * BaseFromTip(q, kRest).translation()).norm(), 1e-9);
}

TEST_F(ManipulatorSceneTest, SensingTheExactTruthGivesQBack) {
  for (int trial = 0; trial < 10; ++trial) {
    const Configuration q = RandomConfiguration(rng_);
    const Pose3 world_from_base = RandomPose(rng_);
    ManipulatorSceneOptions options = trial % 2 == 0 ? ThreeBands() : ManipulatorSceneOptions{};
    options.spacing = 0.1;
    const GroundTruth truth = TruthOf(SceneOfConfiguration(q, kRest, world_from_base, options));
    const ConfigurationMeasurement sensed =
        SenseConfiguration({truth.centerline, {}, truth.marker_arc_length},
                           {kRest, world_from_base, options.tapes}, {});
    ASSERT_TRUE(sensed.valid) << sensed.reason;
    // Only the polyline's chords stand between them.
    EXPECT_LT((sensed.q - q).norm(), 1e-6) << sensed.q.transpose() << " vs " << q.transpose();
  }
}

TEST(ManipulatorSceneOptionsTest, BadOptionsAreNamedAndRefused) {
  ManipulatorSceneOptions options;
  EXPECT_EQ(options.Validate(), "");
  options.band_width = 12.0;
  EXPECT_EQ(options.Validate().rfind("tapes.distal_band_before_tip", 0), 0u) << options.Validate();
  options = ThreeBands();
  options.tapes.proximal_band_before_junction = 5.0;
  EXPECT_EQ(options.Validate().rfind("tapes.proximal_band_before_junction", 0), 0u);
  options = {};
  options.tape_bgr[1] = 300.0;
  EXPECT_EQ(options.Validate().rfind("tape_bgr", 0), 0u);
  options = {};
  options.spacing = 1.0;
  EXPECT_THROW(SceneOfConfiguration(Configuration::Zero(), kRest, Pose3::Identity(), options),
               std::invalid_argument);
  // A band beyond its section, and an impossible strain.
  options = ThreeBands();
  EXPECT_THROW(
      SceneOfConfiguration(Configuration::Zero(), {20.0, 140.0}, Pose3::Identity(), options),
      std::invalid_argument);
  EXPECT_THROW(SceneOfConfiguration(Configuration(0, 0, 0, 1.5), kRest, Pose3::Identity(), {}),
               std::invalid_argument);
}

}  // namespace
}  // namespace shapesense
