// The configuration sensed through the real chain: random configurations
// across the workspace (bends up to 120 degrees in any plane, strains 0-3%),
// rendered by the real renderer (noise, shadows, lens distortion) into a
// synthetic three-camera rig, silhouettes → hierarchical carving at 1 mm →
// ShapeEstimator → SenseConfiguration, against the true q: curvature,
// bending plane, strains, and the tip that the sensed q predicts.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "libs/carving/carver.h"
#include "libs/centerline/shape_estimator.h"
#include "libs/mechanics/configuration_geometry.h"
#include "libs/mechanics/configuration_sensing.h"
#include "libs/silhouette/silhouette.h"
#include "libs/sim/manipulator_scene.h"
#include "libs/sim/scene_generators.h"
#include "libs/sim/tube_scene.h"

namespace shapesense {
namespace {

constexpr double kMaxBend = 120.0 * std::numbers::pi / 180.0;
// Below this bend the relative curvature error and the plane mean little:
// they are checked as absolute errors instead.
constexpr double kSmallBend = 15.0 * std::numbers::pi / 180.0;

// The manipulator enters through the workspace's bottom face at the rig's
// base point, its base axis (y) along world +z, rolled about it by `roll`;
// its base lies `hidden` mm below the face (the part of the proximal section
// the cameras do not see).
Pose3 WorldFromBase(const Rig& rig, double roll, double hidden) {
  Pose3 pose = Pose3::Identity();
  pose.linear() = Eigen::AngleAxisd(roll, Vec3::UnitZ()).toRotationMatrix() *
                  Eigen::AngleAxisd(std::numbers::pi / 2.0, Vec3::UnitX()).toRotationMatrix();
  pose.translation() = rig.base_point - hidden * Vec3::UnitZ();
  return pose;
}

// Every body point (plus the radius and a margin) inside the workspace and
// 8 px inside every image.
bool Fits(const Rig& rig, const TubeScene& scene) {
  const double margin = scene.radius + 4.0;
  for (const Vec3& p : scene.centerline) {
    for (int axis = 0; axis < 2; ++axis) {
      if (p[axis] < rig.workspace_min[axis] + margin || p[axis] > rig.workspace_max[axis] - margin)
        return false;
    }
    if (p.z() > rig.workspace_max.z() - margin) return false;
    for (const Camera& camera : rig.cameras) {
      const auto pixel = camera.Project(p);
      const double radius_px =
          1.1 * scene.radius * camera.camera_matrix(0, 0) / (camera.cam_from_world * p).z();
      if (!pixel || pixel->x() < 8 + radius_px || pixel->y() < 8 + radius_px ||
          pixel->x() > camera.width - 9 - radius_px || pixel->y() > camera.height - 9 - radius_px)
        return false;
    }
  }
  return true;
}

struct Errors {
  double bend = 0.0;           // true bend angle, rad
  double curvature = 0.0;      // relative
  double curvature_abs = 0.0;  // 1/mm
  double plane = 0.0;          // rad
  double eps0 = 0.0, eps1 = 0.0;
  double tip = 0.0;  // mm
  double rms = 0.0;  // arc fit, mm
};

struct Summary {
  std::vector<Errors> all;
  double Worst(double Errors::*field, bool bent_only) const {
    double worst = 0.0;
    for (const Errors& e : all) {
      if (!bent_only || e.bend >= kSmallBend) worst = std::max(worst, e.*field);
    }
    return worst;
  }
  double Mean(double Errors::*field, bool bent_only) const {
    double sum = 0.0;
    int n = 0;
    for (const Errors& e : all) {
      if (bent_only && e.bend < kSmallBend) continue;
      sum += e.*field;
      ++n;
    }
    return n > 0 ? sum / n : 0.0;
  }
};

class ConfigurationChainTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    SyntheticRigOptions options;
    options.seed = 11;
    rig_ = new Rig(MakeSyntheticRig(options));
    carver_ = new Carver(*rig_, CarvingOptions{});
    renderer_ = new SceneRenderer(*rig_);
  }
  static void TearDownTestSuite() {
    delete renderer_;
    delete carver_;
    delete rig_;
  }

  // A random configuration of the manipulator whose scene fits the rig.
  TubeScene DrawScene(const ManipulatorGeometry& geometry, const ManipulatorSceneOptions& scene,
                      double min_bend, std::mt19937& rng) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int draw = 0; draw < 200; ++draw) {
      const double eps1 = 0.03 * unit(rng);
      const double bend = min_bend + (kMaxBend - min_bend) * unit(rng);
      const double kappa = bend / (geometry.rest.distal * (1.0 - eps1));
      const double phi = 2.0 * std::numbers::pi * unit(rng);
      const Configuration q(kappa * std::sin(phi), -kappa * std::cos(phi), 0.03 * unit(rng), eps1);
      TubeScene tube = SceneOfConfiguration(q, geometry.rest, geometry.world_from_base, scene);
      if (Fits(*rig_, tube)) return tube;
    }
    ADD_FAILURE() << "no configuration fits the rig";
    return {};
  }

  ShapeEstimate Measure(const TubeScene& scene, uint32_t seed) {
    const std::vector<RenderedView> views = renderer_->Render(scene, RenderOptions{}, seed);
    const SilhouetteExtractor extractor(SilhouetteOptions{});
    std::vector<Silhouette> silhouettes(views.size());
    for (size_t k = 0; k < views.size(); ++k) {
      extractor.Extract(views[k].image, views[k].background, &silhouettes[k]);
    }
    VoxelCloud cloud;
    carver_->CarveHierarchical(silhouettes, &cloud);
    return ShapeEstimator(*rig_, ShapeOptions{}).Estimate(cloud, silhouettes);
  }

  static ConfigurationMeasurement Sense(const ShapeEstimate& e,
                                        const ManipulatorGeometry& geometry) {
    return SenseConfiguration({e.centerline, e.arc_length, e.marker_arc_length}, geometry, {});
  }

  static Errors Compare(const ConfigurationMeasurement& sensed, const Configuration& q,
                        const ManipulatorGeometry& geometry, const Vec3& true_tip) {
    Errors errors;
    const double kappa = q.head<2>().norm();
    errors.bend = kappa * CompressedLengths(q, geometry.rest).distal;
    errors.curvature_abs = std::abs(sensed.curvature - kappa);
    errors.curvature = kappa > 0.0 ? errors.curvature_abs / kappa : 0.0;
    const double phi = std::atan2(q(kKappaX), -q(kKappaZ));
    errors.plane = std::abs(std::remainder(sensed.bend_direction - phi, 2.0 * std::numbers::pi));
    errors.eps0 = std::abs(sensed.q(kStrainProximal) - q(kStrainProximal));
    errors.eps1 = std::abs(sensed.q(kStrainDistal) - q(kStrainDistal));
    const Vec3 tip = geometry.world_from_base * BaseFromTip(sensed.q, geometry.rest).translation();
    errors.tip = (tip - true_tip).norm();
    errors.rms = sensed.rms_residual;
    return errors;
  }

  // `count` random configurations through the chain; the errors of each.
  Summary Run(const char* name, const ManipulatorGeometry& geometry,
              const ManipulatorSceneOptions& scene_options, int count, uint32_t seed) {
    std::mt19937 rng(seed);
    Summary summary;
    for (int i = 0; i < count; ++i) {
      // One in four bent by 0-120 degrees (nearly straight ones too), the rest
      // by 15-120.
      const TubeScene scene =
          DrawScene(geometry, scene_options, i % 4 == 0 ? 0.0 : kSmallBend, rng);
      if (!scene.configuration) return summary;
      const Configuration& q = *scene.configuration;
      const ShapeEstimate estimate = Measure(scene, seed + static_cast<uint32_t>(i));
      EXPECT_TRUE(estimate.valid) << estimate.error;
      const ConfigurationMeasurement sensed = Sense(estimate, geometry);
      EXPECT_TRUE(sensed.valid) << name << " " << i << ": " << sensed.reason;
      if (!sensed.valid) continue;
      const Errors e = Compare(sensed, q, geometry, TruthOf(scene).tip);
      std::printf(
          "%s %2d: bend %5.1f deg: curvature %.3f%% (%.1e /mm), plane %.4f rad, eps0 %.1e, "
          "eps1 %.1e, tip %.3f mm, arc fit RMS %.3f mm\n",
          name, i, e.bend * 180.0 / std::numbers::pi, 100.0 * e.curvature, e.curvature_abs, e.plane,
          e.eps0, e.eps1, e.tip, e.rms);
      summary.all.push_back(e);
    }
    return summary;
  }

  static void ExpectTargets(const char* name, const Summary& s, int count) {
    ASSERT_EQ(s.all.size(), static_cast<size_t>(count));
    std::printf(
        "%s: worst (mean) curvature %.3f%% (%.3f%%) [bends >= 15 deg], %.1e /mm [all], plane "
        "%.4f (%.4f) rad, eps0 %.1e (%.1e), eps1 %.1e (%.1e), tip %.3f (%.3f) mm\n",
        name, 100.0 * s.Worst(&Errors::curvature, true), 100.0 * s.Mean(&Errors::curvature, true),
        s.Worst(&Errors::curvature_abs, false), s.Worst(&Errors::plane, true),
        s.Mean(&Errors::plane, true), s.Worst(&Errors::eps0, false), s.Mean(&Errors::eps0, false),
        s.Worst(&Errors::eps1, false), s.Mean(&Errors::eps1, false), s.Worst(&Errors::tip, false),
        s.Mean(&Errors::tip, false));
    // The targets: the tip from the sensed q within 0.5 mm, curvature within 1%.
    EXPECT_LT(s.Worst(&Errors::tip, false), 0.5);
    EXPECT_LT(s.Worst(&Errors::curvature, true), 0.01);
    EXPECT_LT(s.Worst(&Errors::curvature_abs, false), 1e-4);
    EXPECT_LT(s.Worst(&Errors::plane, true), 0.01);
    EXPECT_LT(s.Worst(&Errors::eps1, false), 3e-3);
  }

  static Rig* rig_;
  static Carver* carver_;
  static SceneRenderer* renderer_;
};
Rig* ConfigurationChainTest::rig_ = nullptr;
Carver* ConfigurationChainTest::carver_ = nullptr;
SceneRenderer* ConfigurationChainTest::renderer_ = nullptr;

TEST_F(ConfigurationChainTest, ShortProximalSectionWithTheBaseInView) {
  // 60 + 140 mm, the base on the workspace's face: eps0 from the junction
  // band's height over the base.
  ManipulatorGeometry geometry;
  geometry.rest = {60.0, 140.0};
  geometry.world_from_base = WorldFromBase(*rig_, 0.4, 0.0);
  ManipulatorSceneOptions scene;
  scene.tapes = geometry.tapes;
  const Summary s = Run("short", geometry, scene, 12, 100);
  ExpectTargets("short", s, 12);
  EXPECT_LT(s.Worst(&Errors::eps0, false), 1e-2);
}

TEST_F(ConfigurationChainTest, TheCatheterOfTheModelFileWithMostOfItsShaftHidden) {
  // config/manipulator.yaml: 600 + 160 mm; the cameras see the last ~40-60
  // mm of the shaft, the rest below the workspace (drawn as the lead-in).
  ManipulatorGeometry geometry;
  geometry.rest = {600.0, 160.0};
  geometry.world_from_base = WorldFromBase(*rig_, -1.1, 540.0);
  ManipulatorSceneOptions scene;
  scene.body_start = 540.0;
  scene.radius = 2.5;
  scene.tapes = geometry.tapes;
  const Summary s = Run("catheter", geometry, scene, 12, 200);
  ExpectTargets("catheter", s, 12);
  EXPECT_LT(s.Worst(&Errors::eps0, false), 1e-3);
}

TEST_F(ConfigurationChainTest, AHiddenBandGivesTheReasonNotAConfiguration) {
  ManipulatorGeometry geometry;
  geometry.rest = {60.0, 140.0};
  geometry.world_from_base = WorldFromBase(*rig_, 0.0, 0.0);
  ManipulatorSceneOptions scene_options;
  std::mt19937 rng(5);
  TubeScene scene = DrawScene(geometry, scene_options, kSmallBend, rng);
  ASSERT_EQ(scene.tapes.size(), 2u);
  scene.tapes.pop_back();  // the distal band fell off
  const ShapeEstimate estimate = Measure(scene, 5);
  ASSERT_TRUE(estimate.valid) << estimate.error;
  ConfigurationMeasurement sensed = Sense(estimate, geometry);
  EXPECT_FALSE(sensed.valid);
  EXPECT_NE(sensed.reason.find("saw 1 tape markers, the layout has 2"), std::string::npos)
      << sensed.reason;
  // A layout that promises a proximal band the tube does not have.
  geometry.tapes.proximal_band_before_junction = 20.0;
  scene.tapes = SceneOfConfiguration(*scene.configuration, geometry.rest, geometry.world_from_base,
                                     scene_options)
                    .tapes;
  sensed = Sense(Measure(scene, 6), geometry);
  EXPECT_FALSE(sensed.valid);
  EXPECT_NE(sensed.reason.find("saw 2 tape markers, the layout has 3"), std::string::npos)
      << sensed.reason;
}

}  // namespace
}  // namespace shapesense
