// q from a sensed shape, on shapes made from known configurations: exact
// ones come back exactly (any bending plane, bends to 120 degrees, strains
// 0-3%, any base pose, with or without a proximal band, wherever the sensed
// centreline starts); noisy ones within the targets; every bad case says why.
#include "libs/mechanics/configuration_sensing.h"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "libs/geometry/polyline.h"
#include "libs/mechanics/configuration_geometry.h"

namespace shapesense {
namespace {

constexpr SectionLengths kRest{60.0, 140.0};
constexpr double kMaxBend = 120.0 * std::numbers::pi / 180.0;

Pose3 RandomPose(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Pose3 pose = Pose3::Identity();
  pose.linear() = Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized())
                      .toRotationMatrix();
  pose.translation() = 100.0 * Vec3(u(rng), u(rng), u(rng));
  return pose;
}

// Bend up to 120 degrees in any plane, strains 0-3%.
Configuration RandomConfiguration(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double eps1 = 0.03 * unit(rng);
  const double kappa = kMaxBend * unit(rng) / (kRest.distal * (1.0 - eps1));
  const double phi = 2.0 * std::numbers::pi * unit(rng);
  return {kappa * std::sin(phi), -kappa * std::cos(phi), 0.03 * unit(rng), eps1};
}

struct Case {
  ManipulatorGeometry geometry;
  SensedCenterline shape;
};

// Points of q's centreline about 0.1 mm apart (base frame) with their exact
// arc lengths; the junction and the tip are points of it.
void SampleCenterline(const Configuration& q, Polyline* points, std::vector<double>* arc) {
  const SectionLengths compressed = CompressedLengths(q, kRest);
  const int proximal_steps = static_cast<int>(std::ceil(compressed.proximal / 0.1));
  for (int k = 0; k < proximal_steps; ++k) {
    arc->push_back(compressed.proximal * k / proximal_steps);
    points->push_back(Vec3(0.0, arc->back(), 0.0));
  }
  const int distal_steps = static_cast<int>(std::ceil(compressed.distal / 0.1));
  for (int k = 0; k <= distal_steps; ++k) {
    const double s = compressed.distal * k / distal_steps;
    arc->push_back(compressed.proximal + s);
    points->push_back(BaseFromDistalPoint(q, kRest, s).translation());
  }
}

// The shape of q as a perfect sensor would see it, from `start` mm along the
// proximal section (where the cameras' volume begins) to the tip.
Case ExactCase(const Configuration& q, const Pose3& world_from_base, const TapeLayout& tapes,
               double start = 0.0) {
  Case c;
  c.geometry.rest = kRest;
  c.geometry.world_from_base = world_from_base;
  c.geometry.tapes = tapes;
  Polyline base;
  std::vector<double> arc;
  SampleCenterline(q, &base, &arc);
  for (size_t i = 0; i < base.size(); ++i) {
    if (arc[i] < start) continue;
    c.shape.centerline.push_back(world_from_base * base[i]);
    c.shape.arc_length.push_back(arc[i] - start);
  }
  for (const double s : TapeArcLengths(q, kRest, tapes)) {
    c.shape.marker_arc_length.push_back(s - start);
  }
  return c;
}

Vec3 PredictedTip(const ConfigurationMeasurement& sensed, const Case& c) {
  return sensed.world_from_base * BaseFromTip(sensed.q, c.geometry.rest).translation();
}

class ConfigurationSensingTest : public ::testing::Test {
 protected:
  std::mt19937_64 rng_{2024};
};

TEST_F(ConfigurationSensingTest, ExactShapesGiveTheirConfigurationBack) {
  for (int trial = 0; trial < 24; ++trial) {
    TapeLayout tapes;
    tapes.proximal_band_before_junction = trial % 2 == 0 ? 0.0 : 30.0;
    ConfigurationSensingOptions options;
    options.distal_length_from_tip = trial % 3 == 0;
    const Configuration q = RandomConfiguration(rng_);
    const Case c = ExactCase(q, RandomPose(rng_), tapes, trial % 4 == 0 ? 12.0 : 0.0);
    const ConfigurationMeasurement sensed = SenseConfiguration(c.shape, c.geometry, options);
    ASSERT_TRUE(sensed.valid) << sensed.reason;
    EXPECT_LT((sensed.q - q).norm(), 1e-8)
        << "trial " << trial << ": " << sensed.q.transpose() << " vs " << q.transpose();
    EXPECT_LT(sensed.rms_residual, 1e-5);
    EXPECT_NEAR(sensed.measured.distal, CompressedLengths(q, kRest).distal, 1e-9);
    EXPECT_LT((PredictedTip(sensed, c) - c.shape.centerline.back()).norm(), 1e-4);
  }
}

TEST_F(ConfigurationSensingTest, StraightConfigurationsToo) {
  const Configuration q(0.0, 0.0, 0.01, 0.02);
  const Case c = ExactCase(q, RandomPose(rng_), TapeLayout{});
  const ConfigurationMeasurement sensed = SenseConfiguration(c.shape, c.geometry, {});
  ASSERT_TRUE(sensed.valid) << sensed.reason;
  EXPECT_LT((sensed.q - q).norm(), 1e-8);
}

TEST_F(ConfigurationSensingTest, NoisyShapesStayWithinTheTargets) {
  // About what the camera chain delivers: 0.05 mm on the centreline, 0.15 mm
  // on the markers' arc lengths.
  std::normal_distribution<double> centerline_noise(0.0, 0.05), marker_noise(0.0, 0.15);
  double worst_tip = 0.0, worst_kappa = 0.0;
  for (int trial = 0; trial < 20; ++trial) {
    Configuration q = RandomConfiguration(rng_);
    // At least 30 degrees: the relative curvature error of a nearly straight
    // section says nothing.
    const double bend = q.head<2>().norm() * CompressedLengths(q, kRest).distal;
    if (bend < 0.5) q.head<2>() *= 0.5 / bend;
    Case c = ExactCase(q, RandomPose(rng_), TapeLayout{});
    for (Vec3& p : c.shape.centerline)
      p += Vec3(centerline_noise(rng_), centerline_noise(rng_), centerline_noise(rng_));
    for (double& s : c.shape.marker_arc_length) s += marker_noise(rng_);
    const ConfigurationMeasurement sensed = SenseConfiguration(c.shape, c.geometry, {});
    ASSERT_TRUE(sensed.valid) << sensed.reason;
    const Vec3 true_tip = c.geometry.world_from_base * BaseFromTip(q, kRest).translation();
    worst_tip = std::max(worst_tip, (PredictedTip(sensed, c) - true_tip).norm());
    worst_kappa =
        std::max(worst_kappa, std::abs(sensed.curvature - q.head<2>().norm()) / q.head<2>().norm());
  }
  EXPECT_LT(worst_tip, 0.5);
  EXPECT_LT(worst_kappa, 0.01);
  RecordProperty("worst_tip_error_mm", std::to_string(worst_tip));
  RecordProperty("worst_relative_curvature_error", std::to_string(worst_kappa));
}

TEST_F(ConfigurationSensingTest, TheCovarianceCarriesTheStrainsUncertainty) {
  const Case c = ExactCase(RandomConfiguration(rng_), RandomPose(rng_), TapeLayout{});
  ConfigurationSensingOptions options;
  options.marker_std = 0.2;
  const ConfigurationMeasurement sensed = SenseConfiguration(c.shape, c.geometry, options);
  ASSERT_TRUE(sensed.valid) << sensed.reason;
  // eps0 from one marker over L0; eps1 from two markers over L1 - 10 mm.
  EXPECT_NEAR(std::sqrt(sensed.covariance(2, 2)), 0.2 / kRest.proximal, 1e-12);
  EXPECT_NEAR(std::sqrt(sensed.covariance(3, 3)), std::sqrt(2.0) * 0.2 / 130.0, 1e-12);
}

TEST_F(ConfigurationSensingTest, AMissingOrStrayMarkerIsRefusedWithTheReason) {
  const Case c = ExactCase(RandomConfiguration(rng_), RandomPose(rng_), TapeLayout{});
  SensedCenterline missing = c.shape;
  missing.marker_arc_length.pop_back();
  ConfigurationMeasurement sensed = SenseConfiguration(missing, c.geometry, {});
  EXPECT_FALSE(sensed.valid);
  EXPECT_NE(sensed.reason.find("saw 1 tape markers, the layout has 2"), std::string::npos)
      << sensed.reason;
  SensedCenterline stray = c.shape;
  stray.marker_arc_length.push_back(stray.arc_length.back() - 1.0);
  sensed = SenseConfiguration(stray, c.geometry, {});
  EXPECT_FALSE(sensed.valid);
  EXPECT_NE(sensed.reason.find("stray"), std::string::npos) << sensed.reason;
  SensedCenterline none = c.shape;
  none.centerline.clear();
  none.arc_length.clear();
  EXPECT_EQ(SenseConfiguration(none, c.geometry, {}).reason, "no sensed centreline");
}

TEST_F(ConfigurationSensingTest, MarkersThatDoNotFitTheLayoutAreRefused) {
  const Case c = ExactCase(Configuration(0.004, 0.0, 0.01, 0.01), RandomPose(rng_), TapeLayout{});
  // The distal band placed 60 mm before the tip in the layout, 10 mm on the tube.
  ManipulatorGeometry geometry = c.geometry;
  geometry.tapes.distal_band_before_tip = 60.0;
  const ConfigurationMeasurement sensed = SenseConfiguration(c.shape, geometry, {});
  EXPECT_FALSE(sensed.valid);
  EXPECT_NE(sensed.reason.find("do not fit the layout: eps1"), std::string::npos) << sensed.reason;
}

TEST_F(ConfigurationSensingTest, AWrongBasePoseIsNamed) {
  Case c = ExactCase(Configuration(0.004, 0.002, 0.01, 0.01), RandomPose(rng_), TapeLayout{});
  c.geometry.world_from_base.translation() += c.geometry.world_from_base.linear() * Vec3(8, 0, 0);
  const ConfigurationMeasurement sensed = SenseConfiguration(c.shape, c.geometry, {});
  EXPECT_FALSE(sensed.valid);
  EXPECT_NE(sensed.reason.find("off the base axis"), std::string::npos) << sensed.reason;
}

TEST_F(ConfigurationSensingTest, ADistalSectionThatIsNoArcIsRefused) {
  Case c = ExactCase(Configuration(0.008, 0.0, 0.0, 0.0), Pose3::Identity(), TapeLayout{});
  // Bend the far half of the distal section back: an S.
  for (Vec3& p : c.shape.centerline) {
    if (p.y() > kRest.proximal + 70.0) p.z() -= 0.02 * std::pow(p.y() - kRest.proximal - 70.0, 2);
  }
  const ConfigurationMeasurement sensed = SenseConfiguration(c.shape, c.geometry, {});
  EXPECT_FALSE(sensed.valid);
  EXPECT_NE(sensed.reason.find("no arc"), std::string::npos) << sensed.reason;
}

TEST_F(ConfigurationSensingTest, ATooShortDistalSectionIsRefused) {
  const Case c = ExactCase(Configuration(0.004, 0.0, 0.0, 0.0), Pose3::Identity(), TapeLayout{});
  ConfigurationSensingOptions options;
  options.min_distal_length = 200.0;
  const ConfigurationMeasurement sensed = SenseConfiguration(c.shape, c.geometry, options);
  EXPECT_FALSE(sensed.valid);
  EXPECT_NE(sensed.reason.find("too short"), std::string::npos) << sensed.reason;
}

TEST(ConfigurationSensingOptionsTest, ValidationNamesTheKey) {
  ConfigurationSensingOptions options;
  EXPECT_EQ(options.Validate(), "");
  options.arc_fit.max_iterations = 0;
  EXPECT_EQ(options.Validate().rfind("arc_fit.max_iterations", 0), 0u) << options.Validate();
  options = {};
  options.max_strain = 2.0;
  EXPECT_EQ(options.Validate().rfind("max_strain", 0), 0u) << options.Validate();
  ManipulatorGeometry geometry{kRest, Pose3::Identity(), TapeLayout{}};
  EXPECT_EQ(geometry.Validate(), "");
  geometry.tapes.distal_band_before_tip = 150.0;
  EXPECT_EQ(geometry.Validate().rfind("tapes.distal_band_before_tip", 0), 0u)
      << geometry.Validate();
  geometry.tapes = {};
  geometry.rest.distal = -1.0;
  EXPECT_EQ(geometry.Validate().rfind("distal_length", 0), 0u) << geometry.Validate();
  geometry.rest = kRest;
  geometry.world_from_base.linear() *= 2.0;
  EXPECT_EQ(geometry.Validate().rfind("world_from_base", 0), 0u);
  // And SenseConfiguration says so instead of fitting.
  EXPECT_EQ(SenseConfiguration({}, geometry, {}).reason.rfind("world_from_base", 0), 0u);
}

TEST(TapeArcLengthsTest, BandsSitAtTheirRestDistancesScaledByTheirSectionsStrain) {
  TapeLayout tapes;
  tapes.proximal_band_before_junction = 20.0;
  tapes.distal_band_before_tip = 10.0;
  const std::vector<double> arcs = TapeArcLengths(Configuration(0.01, 0.0, 0.1, 0.2), kRest, tapes);
  ASSERT_EQ(arcs.size(), 3u);
  EXPECT_DOUBLE_EQ(arcs[0], 40.0 * 0.9);
  EXPECT_DOUBLE_EQ(arcs[1], 60.0 * 0.9);
  EXPECT_DOUBLE_EQ(arcs[2], 54.0 + 130.0 * 0.8);
}

}  // namespace
}  // namespace shapesense
