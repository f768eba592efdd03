#include "libs/mechanics/stiffness_estimation.h"

#include <gtest/gtest.h>

#include <numbers>
#include <random>
#include <sstream>

#include "libs/mechanics/configuration_geometry.h"
#include "libs/mechanics/synthetic_poses.h"
#include "tests/libs/mechanics/test_models.h"

namespace shapesense {
namespace {

double WorstRelativeError(const StiffnessVector& estimate, const StiffnessVector& truth) {
  return (estimate - truth).cwiseQuotient(truth).cwiseAbs().maxCoeff();
}

// The estimators start from a model that is 40% off in alternating directions.
TendonModel StartingModel(const TendonModel& truth) {
  return truth.WithStiffness(truth.stiffness().cwiseProduct(Eigen::Vector4d(1.4, 0.6, 1.4, 0.6)));
}

class StiffnessEstimationTest : public ::testing::Test {
 protected:
  std::mt19937_64 rng_{777};
};

TEST_F(StiffnessEstimationTest, EveryEstimatorRecoversTheTruthFromExactData) {
  for (int trial = 0; trial < 30; ++trial) {
    const TendonModel truth(testing::RandomOptions(rng_));
    const std::vector<PoseSample> poses = SimulatePoses(truth, SyntheticPoseOptions{}, rng_);
    const TendonModel start = StartingModel(truth);
    for (const StiffnessEstimate& estimate :
         {EstimateStiffnessTensionless(start, poses, EstimationOptions{}),
          EstimateStiffnessFromTensions(start, poses, EstimationOptions{}),
          EstimateStiffnessOutputError(start, poses, EstimationOptions{})}) {
      ASSERT_TRUE(estimate.valid) << estimate.method << ": " << estimate.message;
      EXPECT_LT(WorstRelativeError(estimate.stiffness, truth.stiffness()), 1e-6) << estimate.method;
      EXPECT_LT(estimate.residual_rms.norm(), 1e-9) << estimate.method;
      EXPECT_TRUE(estimate.warnings.empty()) << estimate.method;
    }
    EXPECT_LT(ComputeTipErrors(truth, poses).max, 1e-9);
  }
}

// Statistics of one estimator over many simulated data sets of 26 poses.
struct Spread {
  Eigen::Vector4d mean_error = Eigen::Vector4d::Zero();    // mean estimate / truth - 1
  Eigen::Vector4d actual_std = Eigen::Vector4d::Zero();    // of the estimates / truth
  Eigen::Vector4d reported_std = Eigen::Vector4d::Zero();  // mean reported std / truth
  int data_sets_with_warnings = 0;
};

using Estimator = StiffnessEstimate (*)(const TendonModel&, const std::vector<PoseSample>&,
                                        const EstimationOptions&);

Spread Simulate(Estimator estimator, const TendonModel& truth, const SyntheticPoseOptions& poses,
                int data_sets, uint64_t seed) {
  std::mt19937_64 rng(seed);
  const TendonModel start = StartingModel(truth);
  std::vector<Eigen::Vector4d> relative;
  Spread spread;
  for (int set = 0; set < data_sets; ++set) {
    const StiffnessEstimate estimate =
        estimator(start, SimulatePoses(truth, poses, rng), EstimationOptions{});
    EXPECT_TRUE(estimate.valid) << estimate.message;
    relative.push_back(estimate.stiffness.cwiseQuotient(truth.stiffness()));
    spread.reported_std += estimate.standard_deviation.cwiseQuotient(truth.stiffness()) / data_sets;
    spread.data_sets_with_warnings += estimate.warnings.empty() ? 0 : 1;
  }
  Eigen::Vector4d mean = Eigen::Vector4d::Zero();
  for (const auto& r : relative) mean += r / data_sets;
  for (const auto& r : relative) spread.actual_std += (r - mean).cwiseAbs2() / (data_sets - 1);
  spread.actual_std = spread.actual_std.cwiseSqrt();
  spread.mean_error = mean.array() - 1.0;
  return spread;
}

std::string Describe(const Eigen::Vector4d& v) {
  std::ostringstream out;
  out << (100.0 * v).transpose() << " %";
  return out.str();
}

TEST_F(StiffnessEstimationTest, LowNoiseDataSetsOf26PosesGiveEveryStiffnessWithinTwoPercent) {
  // Sensed curvature to 1e-5 /mm (0.2% of a 45-degree bend), strains to 5e-6.
  const TendonModel truth(testing::CatheterOptions());
  SyntheticPoseOptions poses;
  poses.curvature_noise = 1e-5;
  poses.strain_noise = 5e-6;
  poses.tension_noise = 0.005;
  const TendonModel start = StartingModel(truth);
  for (int set = 0; set < 10; ++set) {
    const std::vector<PoseSample> data = SimulatePoses(truth, poses, rng_);
    ASSERT_EQ(data.size(), 26u);
    for (const StiffnessEstimate& estimate :
         {EstimateStiffnessOutputError(start, data, EstimationOptions{}),
          EstimateStiffnessFromTensions(start, data, EstimationOptions{})}) {
      ASSERT_TRUE(estimate.valid) << estimate.message;
      EXPECT_LT(WorstRelativeError(estimate.stiffness, truth.stiffness()), 0.02) << estimate.method;
      // "The noise allows it": the fit itself says so.
      EXPECT_LT(estimate.standard_deviation.cwiseQuotient(estimate.stiffness).maxCoeff(), 0.01);
      EXPECT_TRUE(estimate.warnings.empty());
    }
  }
}

TEST_F(StiffnessEstimationTest, ReportedStandardDeviationsMatchTheSpreadOverManyDataSets) {
  // 200 data sets of 26 poses; curvature noise 1e-4 /mm, strain noise 5e-5.
  // Measured (bend_x, bend_z, axial_proximal, axial_distal, % of the truth):
  // output error spread 4.3 / 6.2 / 2.4 / 2.2 against reported 4.1 / 6.1 /
  // 2.7 / 2.4; tensions spread 0.55 / 0.75 / 0.32 / 0.14 against reported
  // 0.51 / 0.77 / 0.36 / 0.13.
  const TendonModel truth(testing::CatheterOptions());
  SyntheticPoseOptions poses;
  poses.curvature_noise = 1e-4;
  poses.strain_noise = 5e-5;
  poses.tension_noise = 0.01;
  const std::vector<std::pair<std::string, Estimator>> estimators = {
      {"output_error", &EstimateStiffnessOutputError},
      {"tensions", &EstimateStiffnessFromTensions}};
  for (const auto& [name, estimator] : estimators) {
    const Spread spread = Simulate(estimator, truth, poses, 200, 2024);
    RecordProperty(name + "_actual_std", Describe(spread.actual_std));
    RecordProperty(name + "_reported_std", Describe(spread.reported_std));
    for (int j = 0; j < 4; ++j) {
      // The sample std of 200 estimates is itself uncertain by ~5%.
      const double ratio = spread.actual_std(j) / spread.reported_std(j);
      EXPECT_GT(ratio, 0.85) << name << " " << kStiffnessNames[static_cast<size_t>(j)];
      EXPECT_LT(ratio, 1.15) << name << " " << kStiffnessNames[static_cast<size_t>(j)];
      // Unbiased to within a quarter of the spread.
      EXPECT_LT(std::abs(spread.mean_error(j)), 0.25 * spread.actual_std(j))
          << name << " " << kStiffnessNames[static_cast<size_t>(j)];
    }
  }
}

TEST_F(StiffnessEstimationTest, OutputErrorFitAvoidsTheTensionlessBias) {
  // Noisier sensing (curvature 3e-4 /mm, strains 1e-4): the sensed q on both
  // sides of the tensionless equation biases its bending stiffnesses low
  // (measured -5% and -10%); the output-error fit stays within ~1%.
  const TendonModel truth(testing::CatheterOptions());
  SyntheticPoseOptions poses;
  poses.curvature_noise = 3e-4;
  poses.strain_noise = 1e-4;
  const Spread tensionless = Simulate(&EstimateStiffnessTensionless, truth, poses, 200, 11);
  const Spread output_error = Simulate(&EstimateStiffnessOutputError, truth, poses, 200, 11);
  RecordProperty("tensionless_bias", Describe(tensionless.mean_error));
  RecordProperty("output_error_bias", Describe(output_error.mean_error));
  for (int j = 0; j < 2; ++j) {
    EXPECT_LT(tensionless.mean_error(j), -0.03);
    EXPECT_LT(std::abs(output_error.mean_error(j)), std::abs(tensionless.mean_error(j)) / 3.0);
  }
  // At this noise the bending stiffnesses are poorly identified, and said so.
  EXPECT_EQ(output_error.data_sets_with_warnings, 200);
}

bool HasWarningAbout(const StiffnessEstimate& estimate, const std::string& name) {
  for (const std::string& warning : estimate.warnings) {
    if (warning.rfind(name + " ", 0) == 0) return true;
  }
  return false;
}

TEST_F(StiffnessEstimationTest, WarnsByNameWhenThePosesLeaveAStiffnessUnidentified) {
  // Every pose bends toward +z or -z: nothing exercises the bending about z.
  const TendonModel truth(testing::CatheterOptions());
  SyntheticPoseOptions poses;
  poses.bend_directions = {std::numbers::pi / 2.0, -std::numbers::pi / 2.0};
  poses.curvature_noise = 1e-5;
  poses.strain_noise = 5e-6;
  const StiffnessEstimate estimate =
      EstimateStiffnessOutputError(StartingModel(truth), SimulatePoses(truth, poses, rng_), {});
  ASSERT_EQ(estimate.warnings.size(), 1u);
  EXPECT_TRUE(HasWarningAbout(estimate, "bend_z")) << estimate.warnings[0];
  EXPECT_FALSE(estimate.standard_deviation(kKappaZ) <= 0.1 * estimate.stiffness(kKappaZ));
  EXPECT_LT(std::abs(estimate.stiffness(kKappaX) / truth.stiffness()(kKappaX) - 1.0), 0.02);
}

TEST_F(StiffnessEstimationTest, TipErrorsArePercentagesOfTheDistalLength) {
  const TendonModel truth(testing::CatheterOptions());
  const std::vector<PoseSample> poses = SimulatePoses(truth, SyntheticPoseOptions{}, rng_);
  const TipErrors exact = ComputeTipErrors(truth, poses);
  EXPECT_LT(exact.max, 1e-9);
  const TipErrors wrong = ComputeTipErrors(StartingModel(truth), poses);
  EXPECT_GT(wrong.mean, 1.0);
  EXPECT_GE(wrong.max, wrong.mean);
  ASSERT_EQ(wrong.percent.size(), poses.size());
  const Vec3 predicted =
      BaseFromTip(StartingModel(truth).Forward(poses[5].displacements), truth.lengths())
          .translation();
  const Vec3 sensed = BaseFromTip(poses[5].configuration, truth.lengths()).translation();
  EXPECT_NEAR(wrong.percent[5], 100.0 * (predicted - sensed).norm() / 160.0, 1e-12);
}

TEST_F(StiffnessEstimationTest, RefusesPosesThatDoNotFitTheModel) {
  const TendonModel model(testing::CatheterOptions());
  std::vector<PoseSample> poses = SimulatePoses(model, SyntheticPoseOptions{}, rng_);
  poses[3].displacements.resize(3);
  const StiffnessEstimate estimate = EstimateStiffnessOutputError(model, poses, {});
  EXPECT_FALSE(estimate.valid);
  EXPECT_NE(estimate.message.find("pose 3: expected 4 displacements"), std::string::npos);
  poses = SimulatePoses(model, SyntheticPoseOptions{}, rng_);
  for (PoseSample& pose : poses) pose.tensions.resize(0);
  EXPECT_FALSE(EstimateStiffnessFromTensions(model, poses, {}).valid);
  EXPECT_FALSE(EstimateStiffnessTensionless(model, {poses[0]}, {}).valid);
}

}  // namespace
}  // namespace shapesense
