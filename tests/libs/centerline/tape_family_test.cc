// Tape markers across the renderer's family of looks (libs/sim/look_family.h):
// tape hues and saturations, band widths, body colours, lights and shading
// models, exposure flicker, anti-aliased edges and cameras from 0 to 70° to
// the shaft, with bands at the start of a bend, on a 145° bend and at an
// S-curve's inflection. Every look goes through the same steps, with nothing
// set for it alone: the tape's colour is learnt from a calibration image of
// the straight tube (libs/silhouette/tape_colour.h, among any reds), then the bent scenes go
// through silhouettes, hierarchical carving at 1 mm voxels and the shape estimator, against the
// renderer's truth.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "libs/carving/carver.h"
#include "libs/centerline/shape_estimator.h"
#include "libs/core/error.h"
#include "libs/geometry/polyline.h"
#include "libs/silhouette/silhouette.h"
#include "libs/silhouette/tape_colour.h"
#include "libs/sim/look_family.h"
#include "libs/sim/scene_generators.h"
#include "libs/sim/tube_scene.h"

namespace shapesense {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
constexpr double kRadius = 3.0;

// A scene of the family: a centreline from the rig's base up +z and where
// its bands are centred, mm from the base.
struct SceneCase {
  std::string name;
  Polyline centerline;
  std::vector<double> bands;
};

// The bent scenes measured in every look; the bending plane turns with the
// look so that each look sees its bends from other sides.
std::vector<SceneCase> BentScenes(const Rig& rig, double azimuth) {
  const Vec3 bend(std::cos(azimuth), std::sin(azimuth), 0.0);
  const Vec3 other(std::cos(azimuth + 2.0), std::sin(azimuth + 2.0), 0.0);
  return {
      // 145° over 130 mm; a band where the bend starts, one on it, one near the tip.
      {"arc 145 deg",
       ArcCenterline(rig.base_point, Vec3::UnitZ(), bend, 20.0, 130.0, 145.0 * kDegree),
       {20.0, 80.0, 140.0}},
      // Two 70° arcs of 70 mm; the middle band sits on the inflection.
      {"S-curve",
       SCurveCenterline(rig.base_point, Vec3::UnitZ(), other, 70.0, 70.0 * kDegree, 0.3),
       {22.0, 70.0, 128.0}},
  };
}

TubeScene SceneOf(const SceneCase& scene_case, const Look& look) {
  TubeScene scene;
  scene.centerline = scene_case.centerline;
  scene.radius = kRadius;
  for (const double s : scene_case.bands) scene.tapes.push_back(TapeBand{s, 4.0, {}});
  ApplyLook(look, &scene);
  return scene;
}

// The straight tube the tape's colour is learnt from.
TubeScene CalibrationScene(const Rig& rig, const Look& look) {
  SceneCase straight{"straight",
                     ArcCenterline(rig.base_point, Vec3::UnitZ(), Vec3::UnitX(), 150.0, 0.0, 0.0),
                     {25.0, 75.0, 125.0}};
  return SceneOf(straight, look);
}

std::vector<Silhouette> SilhouettesOf(const std::vector<RenderedView>& views,
                                      const SilhouetteExtractor& extractor) {
  std::vector<Silhouette> silhouettes(views.size());
  for (size_t k = 0; k < views.size(); ++k) {
    extractor.Extract(views[k].image, views[k].background, &silhouettes[k]);
  }
  return silhouettes;
}

// The silhouette options with the tape's colour learnt from one view of the
// calibration scene (the first that shows enough tape), searched for among
// any reds: the same wide prior for every look.
SilhouetteOptions LearntOptions(const std::vector<RenderedView>& views, const std::string& look) {
  SilhouetteOptions options;
  options.tape.hue_deg = {300.0, 60.0};
  options.tape.min_saturation = 0.25;
  options.tape.min_value = 40;
  for (const RenderedView& view : views) {
    try {
      const LearntTapeColour learnt = LearnTapeColour(view.image, view.background, options);
      std::printf("  %s: learnt hue [%.0f, %.0f] deg, saturation >= %.2f, value >= %d\n",
                  look.c_str(), learnt.colour.hue_deg[0], learnt.colour.hue_deg[1],
                  learnt.colour.min_saturation, learnt.colour.min_value);
      options.tape = learnt.colour;
      return options;
    } catch (const InputError&) {
      // Too little tape in this view: the next.
    }
  }
  ADD_FAILURE() << look << ": the tape's colour could not be learnt from any view";
  return options;
}

struct Tally {
  std::vector<double> marker_errors;  // mm, 3-D, every band of every scene
  std::vector<double> strain_errors;  // |measured - true| strain between neighbouring bands
  std::vector<double> centerline_rms;
  std::vector<double> tip_errors;
  int bands_expected = 0;
  int bands_found = 0;

  void Add(const ShapeEstimate& e, const GroundTruth& truth) {
    centerline_rms.push_back(std::max(RmsDistanceToPolyline(e.centerline, truth.centerline),
                                      RmsDistanceToPolyline(truth.centerline, e.centerline)));
    tip_errors.push_back((e.tip - truth.tip).norm());
    bands_expected += static_cast<int>(truth.markers.size());
    bands_found += static_cast<int>(e.markers.size());
    if (e.markers.size() != truth.markers.size()) return;
    for (size_t m = 0; m < e.markers.size(); ++m) {
      marker_errors.push_back((e.markers[m] - truth.markers[m]).norm());
      if (m == 0) continue;
      const double truth_span = truth.marker_arc_length[m] - truth.marker_arc_length[m - 1];
      const double span = e.marker_arc_length[m] - e.marker_arc_length[m - 1];
      strain_errors.push_back(std::abs(span - truth_span) / truth_span);
    }
  }
};

double Mean(const std::vector<double>& values) {
  double sum = 0.0;
  for (const double v : values) sum += v;
  return values.empty() ? 0.0 : sum / static_cast<double>(values.size());
}

double Max(const std::vector<double>& values) {
  return values.empty() ? 0.0 : *std::max_element(values.begin(), values.end());
}

Tally MeasureLook(const Look& look, uint32_t seed) {
  SyntheticRigOptions rig_options;
  rig_options.seed = seed;
  rig_options.workspace_half_size = 110.0;
  rig_options.elevation_deg = look.elevation_deg;
  const Rig rig = MakeSyntheticRig(rig_options);
  const SceneRenderer renderer(rig);
  const SilhouetteExtractor extractor(
      LearntOptions(renderer.Render(CalibrationScene(rig, look), look.render, seed), look.name));
  const Carver carver(rig, CarvingOptions{});
  ShapeOptions shape_options;
  shape_options.band_width = look.band_width;
  const ShapeEstimator estimator(rig, shape_options);
  Tally tally;
  const std::vector<SceneCase> scenes = BentScenes(rig, 0.9 * seed);
  for (size_t i = 0; i < scenes.size(); ++i) {
    const TubeScene scene = SceneOf(scenes[i], look);
    const std::vector<Silhouette> silhouettes = SilhouettesOf(
        renderer.Render(scene, look.render, seed * 10 + static_cast<uint32_t>(i)), extractor);
    VoxelCloud cloud;
    carver.CarveHierarchical(silhouettes, &cloud);
    const ShapeEstimate e = estimator.Estimate(cloud, silhouettes);
    EXPECT_TRUE(e.valid) << look.name << ", " << scenes[i].name << ": " << e.error;
    if (!e.valid) continue;
    const GroundTruth truth = TruthOf(scene);
    EXPECT_EQ(e.markers.size(), truth.markers.size())
        << look.name << ", " << scenes[i].name << ": a band missing or extra";
    tally.Add(e, truth);
  }
  return tally;
}

// Merges one look's tally into the family's.
void Append(const Tally& look, Tally* all) {
  const auto append = [](const std::vector<double>& from, std::vector<double>* to) {
    to->insert(to->end(), from.begin(), from.end());
  };
  append(look.marker_errors, &all->marker_errors);
  append(look.strain_errors, &all->strain_errors);
  append(look.centerline_rms, &all->centerline_rms);
  append(look.tip_errors, &all->tip_errors);
  all->bands_expected += look.bands_expected;
  all->bands_found += look.bands_found;
}

TEST(TapeFamilyTest, EveryBandOfEveryLookWithinAFewTenthsOfAMillimetre) {
  const std::vector<Look> family = LookFamily();
  Tally all;
  std::printf("%-78s %6s %9s %9s %10s %9s %7s\n", "look", "bands", "tape mean", "tape max",
              "strain |e|", "line RMS", "tip");
  for (size_t i = 0; i < family.size(); ++i) {
    const Tally look = MeasureLook(family[i], static_cast<uint32_t>(i + 1));
    std::printf("%-78s %2d/%-3d %6.3f mm %6.3f mm %8.3f %% %6.3f mm %4.2f mm\n",
                family[i].name.c_str(), look.bands_found, look.bands_expected,
                Mean(look.marker_errors), Max(look.marker_errors), 100.0 * Mean(look.strain_errors),
                Mean(look.centerline_rms), Max(look.tip_errors));
    Append(look, &all);
  }
  std::printf(
      "family: %d/%d bands, tape centres %.3f mm mean, %.3f mm max; strain %.3f %% mean "
      "|error|, %.3f %% max; centreline RMS %.3f mm mean; tip %.3f mm mean, %.3f mm max\n",
      all.bands_found, all.bands_expected, Mean(all.marker_errors), Max(all.marker_errors),
      100.0 * Mean(all.strain_errors), 100.0 * Max(all.strain_errors), Mean(all.centerline_rms),
      Mean(all.tip_errors), Max(all.tip_errors));
  EXPECT_EQ(all.bands_found, all.bands_expected);
  EXPECT_LE(Mean(all.marker_errors), 0.3);
  EXPECT_LE(Max(all.marker_errors), 0.6);
  EXPECT_LE(Mean(all.strain_errors), 0.003);
  // As on the project's own look (shape_estimator_chain_test.cc).
  EXPECT_LE(Mean(all.centerline_rms), 0.1);
  EXPECT_LE(Max(all.tip_errors), 1.0);
}

}  // namespace
}  // namespace shapesense
