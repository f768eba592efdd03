// The shape estimator through the real chain: rendered images (noise,
// shadows, lens distortion) → silhouettes → hierarchical carving at 1 mm
// voxels → shape, against the renderer's exact ground truth.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <vector>

#include "libs/carving/carver.h"
#include "libs/centerline/shape_estimator.h"
#include "libs/geometry/polyline.h"
#include "libs/silhouette/compact_silhouette.h"
#include "libs/silhouette/silhouette.h"
#include "libs/sim/scene_generators.h"
#include "libs/sim/tube_scene.h"

namespace shapesense {
namespace {

constexpr double kMaxBend = 150.0 * std::numbers::pi / 180.0;

struct RigCase {
  SyntheticRigOptions options;
  int scenes = 3;
  RenderOptions render;
};

struct Errors {
  double centerline_rms = 0.0;  // the larger of the two directions, mm
  double tip = 0.0;
  double worst_marker = 0.0;
};

// Both ways (estimate to truth and truth to estimate), so an estimate that
// is short cannot look good.
double TwoWayRms(const Polyline& estimate, const Polyline& truth) {
  return std::max(RmsDistanceToPolyline(estimate, truth), RmsDistanceToPolyline(truth, estimate));
}

Errors Measure(const ShapeEstimate& e, const GroundTruth& truth) {
  Errors errors;
  errors.centerline_rms = TwoWayRms(e.centerline, truth.centerline);
  errors.tip = (e.tip - truth.tip).norm();
  for (size_t m = 0; m < truth.markers.size() && m < e.markers.size(); ++m) {
    errors.worst_marker = std::max(errors.worst_marker, (e.markers[m] - truth.markers[m]).norm());
  }
  return errors;
}

// The silhouettes as the shape service receives them: compacted by the
// carving service and expanded again. Prints their size on the wire's order.
std::vector<Silhouette> ThroughCompaction(const std::vector<Silhouette>& silhouettes) {
  std::vector<Silhouette> expanded(silhouettes.size());
  CompactScratch scratch;
  size_t bytes = 0;
  for (size_t k = 0; k < silhouettes.size(); ++k) {
    CompactSilhouette compact;
    Compact(silhouettes[k], &compact, &scratch);
    EXPECT_EQ(Validate(compact), "");
    bytes += 6 * (compact.mask.size() + compact.markers.size() + compact.band.size()) +
             compact.band_difference.size();
    Expand(compact, &expanded[k]);
  }
  std::printf("compact silhouettes: %zu bytes\n", bytes);
  return expanded;
}

// Bit for bit: the compaction keeps everything the estimate reads.
void ExpectSameEstimate(const ShapeEstimate& a, const ShapeEstimate& b) {
  ASSERT_EQ(a.valid, b.valid);
  ASSERT_EQ(a.centerline.size(), b.centerline.size());
  for (size_t i = 0; i < a.centerline.size(); ++i) EXPECT_EQ(a.centerline[i], b.centerline[i]);
  EXPECT_EQ(a.tip, b.tip);
  EXPECT_EQ(a.tube_radius, b.tube_radius);
  ASSERT_EQ(a.markers.size(), b.markers.size());
  for (size_t m = 0; m < a.markers.size(); ++m) EXPECT_EQ(a.markers[m], b.markers[m]);
}

class ChainTest : public ::testing::Test {
 protected:
  // Every scene of one rig through the chain; returns the errors per scene.
  std::vector<Errors> RunRig(const RigCase& rig_case, uint32_t scene_seed) {
    const Rig rig = MakeSyntheticRig(rig_case.options);
    const Carver carver(rig, CarvingOptions{});
    const SilhouetteExtractor extractor(SilhouetteOptions{});
    const ShapeEstimator estimator(rig, ShapeOptions{});
    std::vector<Errors> all;
    for (int s = 0; s < rig_case.scenes; ++s) {
      const TubeScene scene = RandomScene(rig, scene_seed + static_cast<uint32_t>(s), kMaxBend, 3);
      const GroundTruth truth = TruthOf(scene);
      const std::vector<RenderedView> views =
          RenderScene(rig, scene, rig_case.render, scene_seed + static_cast<uint32_t>(s));
      std::vector<Silhouette> silhouettes(views.size());
      for (size_t k = 0; k < views.size(); ++k) {
        extractor.Extract(views[k].image, views[k].background, &silhouettes[k]);
      }
      VoxelCloud cloud;
      carver.CarveHierarchical(silhouettes, &cloud);
      const ShapeEstimate e = estimator.Estimate(cloud, silhouettes);
      EXPECT_TRUE(e.valid) << e.error;
      ExpectSameEstimate(e, estimator.Estimate(cloud, ThroughCompaction(silhouettes)));
      if (!e.valid) continue;
      const Errors errors = Measure(e, truth);
      std::printf(
          "rig %u (%d cameras) scene %d: %zu voxels, length %.0f mm, radius %.2f (est. %.3f): "
          "centreline RMS %.3f mm, tip %.3f mm, markers %zu/%zu worst %.3f mm\n",
          rig_case.options.seed, rig_case.options.num_cameras, s, cloud.voxels.size(), truth.length,
          scene.radius, e.tube_radius, errors.centerline_rms, errors.tip, e.markers.size(),
          truth.markers.size(), errors.worst_marker);
      // The targets.
      EXPECT_LT(errors.centerline_rms, 0.5);
      EXPECT_LT(errors.tip, 1.0);
      EXPECT_EQ(e.markers.size(), truth.markers.size());
      EXPECT_LT(errors.worst_marker, 1.0);
      EXPECT_NEAR(e.length, truth.length, 1.0);
      EXPECT_NEAR(e.tube_radius, scene.radius, 0.1);
      all.push_back(errors);
    }
    return all;
  }

  static void ExpectAimMet(const std::vector<Errors>& all) {
    ASSERT_FALSE(all.empty());
    double sum = 0.0;
    for (const Errors& e : all) sum += e.centerline_rms;
    // The aim, on average: a fifth of a voxel.
    EXPECT_LT(sum / static_cast<double>(all.size()), 0.2);
  }
};

TEST_F(ChainTest, ThreeCamerasWithDistortionNoiseAndShadows) {
  RigCase rig_case;
  rig_case.options.seed = 1;
  rig_case.options.workspace_half_size = 110.0;
  rig_case.options.num_cameras = 3;
  ExpectAimMet(RunRig(rig_case, 100));
}

TEST_F(ChainTest, FourCamerasAndAnotherRig) {
  RigCase rig_case;
  rig_case.options.seed = 2;
  rig_case.options.workspace_half_size = 110.0;
  rig_case.options.num_cameras = 4;
  rig_case.options.elevation_deg = 30.0;
  ExpectAimMet(RunRig(rig_case, 200));
}

TEST_F(ChainTest, HarderImagesNoisierWithDarkerShadows) {
  RigCase rig_case;
  rig_case.options.seed = 3;
  rig_case.options.workspace_half_size = 110.0;
  rig_case.options.num_cameras = 3;
  rig_case.options.distance = 500.0;
  rig_case.render.noise_sigma = 4.0;
  rig_case.render.shadow_strength = 0.5;
  ExpectAimMet(RunRig(rig_case, 300));
}

}  // namespace
}  // namespace shapesense
