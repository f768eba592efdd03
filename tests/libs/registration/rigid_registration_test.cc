#include "libs/registration/rigid_registration.h"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "libs/mechanics/configuration_geometry.h"
#include "libs/mechanics/tendon_model.h"

namespace shapesense {
namespace {

class RegistrationTest : public ::testing::Test {
 protected:
  Pose3 RandomPose() {
    std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi),
        offset(-300, 300);
    std::normal_distribution<double> normal;
    const Vec3 axis = Vec3(normal(rng_), normal(rng_), normal(rng_)).normalized();
    Pose3 pose = Pose3::Identity();
    pose.linear() = Eigen::AngleAxisd(angle(rng_), axis).toRotationMatrix();
    pose.translation() = Vec3(offset(rng_), offset(rng_), offset(rng_));
    return pose;
  }
  Polyline RandomPoints(int count) {
    std::uniform_real_distribution<double> u(-100.0, 100.0);
    Polyline points;
    for (int i = 0; i < count; ++i) points.push_back(Vec3(u(rng_), u(rng_), u(rng_)));
    return points;
  }
  Polyline Moved(const Pose3& pose, const Polyline& points, const Vec3& noise = Vec3::Zero()) {
    std::normal_distribution<double> normal;
    Polyline out;
    for (const Vec3& p : points) {
      out.push_back(pose * p + noise.cwiseProduct(Vec3(normal(rng_), normal(rng_), normal(rng_))));
    }
    return out;
  }
  static double RotationError(const Pose3& a, const Pose3& b) {
    return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
  }

  std::mt19937_64 rng_{4242};
};

TEST_F(RegistrationTest, RecoversAKnownPoseExactlyFromExactData) {
  for (int trial = 0; trial < 100; ++trial) {
    const Pose3 truth = RandomPose();
    const Polyline source = RandomPoints(3 + trial % 20);
    for (const double loss : {0.0, 1.0}) {
      RegistrationOptions options;
      options.loss_scale = loss;
      const Registration result = RegisterPointSets(source, Moved(truth, source), options);
      ASSERT_TRUE(result.converged) << result.message;
      EXPECT_LT(RotationError(result.target_from_source, truth), 1e-9);
      EXPECT_LT((result.target_from_source.translation() - truth.translation()).norm(), 1e-9);
      EXPECT_LT(result.rms, 1e-9);
      // Orthonormal and proper by construction.
      const Mat3 r = result.target_from_source.linear();
      EXPECT_LT((r.transpose() * r - Mat3::Identity()).norm(), 1e-12);
      EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
    }
  }
}

TEST_F(RegistrationTest, ReportsTheRmsErrorPerAxisOnNoisyData) {
  // Anisotropic noise, 0.05 / 0.1 / 0.2 mm: each axis's RMS shows its own.
  const Vec3 noise(0.05, 0.1, 0.2);
  for (int trial = 0; trial < 10; ++trial) {
    const Pose3 truth = RandomPose();
    const Polyline source = RandomPoints(2000);
    const Registration result = RegisterPointSets(source, Moved(truth, source, noise), {});
    ASSERT_TRUE(result.converged);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(result.rms_per_axis(k), noise(k), 0.1 * noise(k));
    EXPECT_NEAR(result.rms, noise.norm(), 0.05 * noise.norm());
    EXPECT_LT(RotationError(result.target_from_source, truth), 1e-3);
    EXPECT_LT((result.target_from_source.translation() - truth.translation()).norm(), 0.1);
  }
}

TEST_F(RegistrationTest, HuberLossResistsStrayPairs) {
  const Pose3 truth = RandomPose();
  const Polyline source = RandomPoints(200);
  Polyline target = Moved(truth, source, Vec3::Constant(0.05));
  for (size_t i = 0; i < target.size(); i += 10) target[i] += Vec3(20.0, -15.0, 10.0);
  RegistrationOptions robust;
  robust.loss_scale = 0.5;
  const Registration plain = RegisterPointSets(source, target, {});
  const Registration huber = RegisterPointSets(source, target, robust);
  ASSERT_TRUE(huber.converged);
  EXPECT_LT((huber.target_from_source.translation() - truth.translation()).norm(), 0.15);
  EXPECT_LT(RotationError(huber.target_from_source, truth), 5e-4);
  EXPECT_GT((plain.target_from_source.translation() - truth.translation()).norm(), 0.5);
}

TEST_F(RegistrationTest, RefusesDegeneratePointSets) {
  Polyline line;
  for (int i = 0; i < 10; ++i) line.push_back(Vec3(i, 2.0 * i, -i));
  EXPECT_NE(RegisterPointSets(line, line, {}).message.find("one line"), std::string::npos);
  EXPECT_FALSE(RegisterPointSets(RandomPoints(5), RandomPoints(6), {}).converged);
  EXPECT_FALSE(RegisterPointSets(RandomPoints(2), RandomPoints(2), {}).converged);
}

// The reference's frame registration: articulate toward each tendon, sense
// the arcs in the world frame, register the model's arcs onto them.
TEST_F(RegistrationTest, FrameRegistrationFromTendonArticulations) {
  ManipulatorOptions options;
  options.proximal_length = 600.0;
  options.distal_length = 160.0;
  for (int i = 0; i < 4; ++i) {
    const double a = i * std::numbers::pi / 2.0;
    options.tendons.push_back({1.2 * std::cos(a), 1.2 * std::sin(a), 900.0, 6000.0});
  }
  const TendonModel model(options);
  const Pose3 world_from_base = RandomPose();
  std::vector<Polyline> model_arcs, sensed_arcs;
  for (const Eigen::VectorXd& y : TendonArticulations(model, 1.0, 0.5)) {
    const Polyline arc = DistalCenterline(model.Forward(y), model.lengths(), 1.0);
    model_arcs.push_back(arc);
    sensed_arcs.push_back(Moved(world_from_base, arc, Vec3::Constant(0.1)));
  }
  const Registration result = RegisterCurves(model_arcs, sensed_arcs, 40, {});
  ASSERT_TRUE(result.converged) << result.message;
  EXPECT_LT(RotationError(result.target_from_source, world_from_base), 2e-3);
  EXPECT_LT((result.target_from_source.translation() - world_from_base.translation()).norm(), 1.0);
  // Where the manipulator is (the arcs), the frames agree to a fraction of a mm.
  for (const Polyline& arc : model_arcs) {
    EXPECT_LT((result.target_from_source * arc.back() - world_from_base * arc.back()).norm(), 0.2);
  }
  EXPECT_LT(result.rms_per_axis.maxCoeff(), 0.3);
}

}  // namespace
}  // namespace shapesense
