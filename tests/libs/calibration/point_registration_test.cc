// Rigid registration over random transforms and point sets: exact recovery,
// the error statistics, symmetry, robustness, and sets that fix no rotation.
#include "libs/calibration/point_registration.h"

#include <gtest/gtest.h>

#include <random>

#include "libs/core/error.h"

namespace shapesense {
namespace {

Pose3 RandomPose(std::mt19937& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  const Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
  Pose3 pose = Pose3::Identity();
  pose.linear() = q.normalized().toRotationMatrix();
  pose.translation() = 200.0 * Vec3(normal(rng), normal(rng), normal(rng));
  return pose;
}

std::vector<Vec3> RandomPoints(std::mt19937& rng, int count) {
  std::uniform_real_distribution<double> coordinate(-150.0, 150.0);
  std::vector<Vec3> points(static_cast<size_t>(count));
  for (Vec3& p : points) p = Vec3(coordinate(rng), coordinate(rng), coordinate(rng));
  return points;
}

std::vector<Vec3> Moved(const Pose3& pose, const std::vector<Vec3>& points) {
  std::vector<Vec3> moved(points.size());
  for (size_t i = 0; i < points.size(); ++i) moved[i] = pose * points[i];
  return moved;
}

double PoseDistance(const Pose3& a, const Pose3& b) { return (a.matrix() - b.matrix()).norm(); }

TEST(PointRegistrationTest, RecoversRandomTransformsExactlyWithoutNoise) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    const Pose3 truth = RandomPose(rng);
    const std::vector<Vec3> sensed = RandomPoints(rng, 3 + trial);
    const std::vector<Vec3> reference = Moved(truth, sensed);
    const PointRegistration result = RegisterPoints(sensed, reference);
    EXPECT_LT(PoseDistance(result.reference_from_sensed, truth), 1e-8) << trial;
    EXPECT_LT(result.rms, 1e-8);
    EXPECT_NEAR(result.reference_from_sensed.linear().determinant(), 1.0, 1e-12);
  }
}

TEST(PointRegistrationTest, ErrorStatisticsDescribeTheResiduals) {
  std::mt19937 rng(2);
  std::normal_distribution<double> noise(0.0, 0.3);
  for (int trial = 0; trial < 10; ++trial) {
    const Pose3 truth = RandomPose(rng);
    const std::vector<Vec3> sensed = RandomPoints(rng, 12);
    std::vector<Vec3> reference = Moved(truth, sensed);
    for (Vec3& p : reference) p += Vec3(noise(rng), noise(rng), noise(rng));
    const PointRegistration result = RegisterPoints(sensed, reference);
    Vec3 sum_squares = Vec3::Zero();
    double largest = 0.0;
    for (size_t i = 0; i < sensed.size(); ++i) {
      const Vec3 error = result.reference_from_sensed * sensed[i] - reference[i];
      EXPECT_LT((error - result.errors[i]).norm(), 1e-9);
      sum_squares += error.cwiseAbs2();
      largest = std::max(largest, error.norm());
    }
    EXPECT_LT((result.rms_per_axis - (sum_squares / 12.0).cwiseSqrt()).norm(), 1e-9);
    EXPECT_NEAR(result.rms * result.rms, result.rms_per_axis.squaredNorm(), 1e-9);
    EXPECT_NEAR(result.max_error, largest, 1e-9);
    // Least squares: no other transform fits better, the truth included.
    double truth_sum = 0.0;
    for (size_t i = 0; i < sensed.size(); ++i) {
      truth_sum += (truth * sensed[i] - reference[i]).squaredNorm();
    }
    EXPECT_LE(result.rms, std::sqrt(truth_sum / 12.0) + 1e-9);
    // Swapping the sets gives the inverse transform.
    const PointRegistration swapped = RegisterPoints(reference, sensed);
    EXPECT_LT(PoseDistance(swapped.reference_from_sensed, result.reference_from_sensed.inverse()),
              1e-6);
  }
}

TEST(PointRegistrationTest, HuberLossKeepsAGrossOutlierFromPullingTheFit) {
  std::mt19937 rng(3);
  const Pose3 truth = RandomPose(rng);
  const std::vector<Vec3> sensed = RandomPoints(rng, 15);
  std::vector<Vec3> reference = Moved(truth, sensed);
  reference[4] += Vec3(40.0, -30.0, 25.0);  // a digitizer point taken at the wrong place
  RegistrationOptions robust;
  robust.loss_scale = 1.0;
  const PointRegistration plain = RegisterPoints(sensed, reference);
  const PointRegistration result = RegisterPoints(sensed, reference, robust);
  EXPECT_LT(PoseDistance(result.reference_from_sensed, truth),
            0.1 * PoseDistance(plain.reference_from_sensed, truth));
  EXPECT_GT(result.errors[4].norm(), 50.0);  // and it stands out in the report
}

TEST(PointRegistrationTest, SetsThatFixNoRotationAreInputErrors) {
  const std::vector<Vec3> line = {Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(2, 2, 2), Vec3(5, 5, 5)};
  EXPECT_THROW(RegisterPoints(line, line), InputError);
  const std::vector<Vec3> two = {Vec3(0, 0, 0), Vec3(1, 0, 0)};
  EXPECT_THROW(RegisterPoints(two, two), InputError);
  const std::vector<Vec3> three = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  EXPECT_THROW(RegisterPoints(three, line), InputError);
  EXPECT_NO_THROW(RegisterPoints(three, three));
  RegistrationOptions bad;
  bad.loss_scale = -1.0;
  EXPECT_NE(bad.Validate().find("loss_scale:"), std::string::npos);
}

}  // namespace
}  // namespace shapesense
