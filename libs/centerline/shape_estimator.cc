#include "libs/centerline/shape_estimator.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "libs/centerline/block_geodesic.h"
#include "libs/centerline/curve_measures.h"
#include "libs/centerline/markers.h"
#include "libs/centerline/silhouette_refiner.h"
#include "libs/centerline/smoothing_spline.h"
#include "libs/centerline/voxel_body.h"
#include "libs/geometry/polyline.h"

namespace shapesense {
namespace {

constexpr int kMinBodyVoxels = 20;
constexpr int kMinSlices = 4;
// Seeds of the geodesic search: voxels this many voxel sizes farther from the
// base point than the nearest one.
constexpr double kSeedMarginVoxels = 2.0;
// A point the silhouettes could not refine still holds the spline across the
// gap, but barely pulls it.
constexpr double kUnrefinedWeight = 0.05;
// Farthest an edge's ray may pass from the tube's surface around the current
// axis, mm: on the first pass the axis comes from the voxels (within about a
// voxel) and the radius may be the visual hull's (a little large); after it,
// the axis is within a tenth of a millimetre.
constexpr double kFirstPassEdgeOffsetMm = 1.5;
constexpr double kEdgeOffsetMm = 0.5;
// Farthest the start is extended back to the workspace face, voxels.
constexpr double kMaxBaseExtensionVoxels = 3.0;
// Axis points refined per knot span of the spline: enough to average the
// edge noise, few enough to keep the edge searches cheap.
constexpr double kRefinedPointsPerKnot = 2.5;
// Below this fraction of centreline points that the silhouettes confirm, the
// visual hull is not the tube's and the estimate is refused.
constexpr double kMinRefinedFraction = 0.5;
// Tape bands closer than this along the body merge, voxels.
constexpr double kMarkerGapVoxels = 2.5;

ShapeEstimate Failure(const std::string& error) {
  ShapeEstimate estimate;
  estimate.error = error;
  return estimate;
}

// The centreline as a spline and the parameter range of the body on it.
struct Curve {
  SmoothingSpline spline;
  double begin = 0.0;
  double end = 0.0;
};

std::string CheckInputs(const Rig& rig, const VoxelCloud& cloud,
                        const std::vector<Silhouette>& silhouettes) {
  if (cloud.voxels.empty()) return "the voxel cloud is empty";
  if (cloud.labels.size() != cloud.voxels.size()) {
    return "the voxel cloud has " + std::to_string(cloud.labels.size()) + " labels for " +
           std::to_string(cloud.voxels.size()) + " voxels";
  }
  const VoxelGrid& grid = cloud.grid;
  if (!(grid.voxel_size > 0.0) || grid.dims[0] <= 0 || grid.dims[1] <= 0 || grid.dims[2] <= 0) {
    return "the voxel grid is empty or has a non-positive voxel size";
  }
  if (!std::is_sorted(cloud.voxels.begin(), cloud.voxels.end()) || cloud.voxels.front() < 0 ||
      cloud.voxels.back() >= grid.NumVoxels() ||
      std::adjacent_find(cloud.voxels.begin(), cloud.voxels.end()) != cloud.voxels.end()) {
    return "the voxel indices must be ascending, distinct and inside the grid";
  }
  if (!silhouettes.empty() && silhouettes.size() != rig.cameras.size()) {
    return "got " + std::to_string(silhouettes.size()) + " silhouettes for " +
           std::to_string(rig.cameras.size()) + " cameras";
  }
  for (size_t k = 0; k < silhouettes.size(); ++k) {
    const Silhouette& s = silhouettes[k];
    const Camera& camera = rig.cameras[k];
    if (s.mask.type() != CV_8U || s.difference.type() != CV_8U || s.mask.cols != camera.width ||
        s.mask.rows != camera.height || s.difference.size != s.mask.size) {
      return "silhouette " + std::to_string(k) + " is not a " + std::to_string(camera.width) + "x" +
             std::to_string(camera.height) + " 8-bit mask and difference image";
    }
  }
  return {};
}

// Mean radius of the visual hull: its volume over its length.
double HullRadius(const GeodesicBody& body, double voxel_size, double length) {
  const double volume = static_cast<double>(body.members.size()) * std::pow(voxel_size, 3);
  return std::sqrt(volume / (std::numbers::pi * std::max(length, voxel_size)));
}

// The face of the workspace (axis, coordinate of the plane) that most of the
// seeds lie against; axis -1 when they touch none.
std::pair<int, double> BaseFace(const VoxelGrid& grid, const VoxelGraph& graph,
                                const std::vector<int32_t>& seeds) {
  std::array<int, 6> touching{};
  for (const int32_t s : seeds) {
    const std::array<int, 3>& c = graph.coordinates(s);
    for (int axis = 0; axis < 3; ++axis) {
      if (c[static_cast<size_t>(axis)] == 0) ++touching[2 * static_cast<size_t>(axis)];
      if (c[static_cast<size_t>(axis)] == grid.dims[static_cast<size_t>(axis)] - 1) {
        ++touching[2 * static_cast<size_t>(axis) + 1];
      }
    }
  }
  const auto most = std::max_element(touching.begin(), touching.end());
  if (*most == 0) return {-1, 0.0};
  const int face = static_cast<int>(most - touching.begin());
  const int axis = face / 2;
  const double low = grid.origin[axis] - 0.5 * grid.voxel_size;
  const double high = low + grid.dims[static_cast<size_t>(axis)] * grid.voxel_size;
  return {axis, face % 2 == 0 ? low : high};
}

// Where the body starts: the parameter at which the spline, continued back
// along its tangent, meets the workspace face that cuts the body at the base.
double StartParameter(const Curve& curve, const VoxelGrid& grid, const VoxelGraph& graph,
                      const GeodesicBody& body) {
  const auto [axis, plane] = BaseFace(grid, graph, body.seeds);
  const double u0 = curve.spline.begin();
  if (axis < 0) return u0;
  const Vec3 p = curve.spline.Point(u0);
  const Vec3 d = curve.spline.Derivative(u0);
  if (std::abs(d[axis]) < 0.3 * d.norm()) return u0;  // the axis runs along the face
  const double u = u0 + (plane - p[axis]) / d[axis];
  return std::clamp(u, u0 - kMaxBaseExtensionVoxels * grid.voxel_size / d.norm(), u0);
}

// The first centreline: a spline through the centroids of the slices of equal
// geodesic distance, from the workspace face (when the body is cut there) to
// one hull radius before the body's far end (the centre of the cap).
Curve InitialCurve(const std::vector<BodySlice>& slices, const VoxelCloud& cloud,
                   const VoxelGraph& graph, const GeodesicBody& body, const ShapeOptions& options,
                   double hull_radius) {
  std::vector<double> u;
  Polyline points;
  for (const BodySlice& slice : slices) {
    u.push_back(slice.distance);
    points.push_back(slice.centroid);
  }
  Curve curve;
  curve.spline = SmoothingSpline::Fit(u, points, {}, options.knot_spacing, options.smoothing);
  if (curve.spline.empty()) return curve;
  curve.begin = StartParameter(curve, cloud.grid, graph, body);
  float far = 0.0f;
  for (const int32_t i : body.members) far = std::max(far, body.distance[static_cast<size_t>(i)]);
  curve.end = std::max(curve.begin + cloud.grid.voxel_size, far - hull_radius);
  return curve;
}

struct Samples {
  Polyline points;
  std::vector<double> params;
  std::vector<double> arc;
  Polyline tangents;
};

Samples SampleCurve(const Curve& curve, double spacing) {
  Samples samples;
  samples.points =
      SampleByArcLength(curve.spline, curve.begin, curve.end, spacing, &samples.params);
  samples.arc = CumulativeArcLength(samples.points);
  for (const double u : samples.params) {
    samples.tangents.push_back(curve.spline.Derivative(u).normalized());
  }
  return samples;
}

// y at x by linear interpolation in the table (xs ascending), clamped.
double Interpolate(const std::vector<double>& xs, const std::vector<double>& ys, double x) {
  if (x <= xs.front()) return ys.front();
  if (x >= xs.back()) return ys.back();
  const size_t i = static_cast<size_t>(std::upper_bound(xs.begin(), xs.end(), x) - xs.begin());
  const double f = (x - xs[i - 1]) / (xs[i] - xs[i - 1]);
  return ys[i - 1] + f * (ys[i] - ys[i - 1]);
}

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// One pass of the refinement: every sample's axis point against the edges
// around it; the radius too on the first pass when it is unknown.
std::vector<AxisPointFit> FitSamples(const SilhouetteRefiner& refiner, const Curve& curve,
                                     const Samples& samples, bool first_pass, bool estimate_radius,
                                     double* radius) {
  std::vector<std::vector<EdgeConstraint>> edges(samples.points.size());
  const double max_offset = first_pass ? kFirstPassEdgeOffsetMm : kEdgeOffsetMm;
  for (size_t i = 0; i < samples.points.size(); ++i) {
    refiner.FindEdges(curve.spline, samples.params[i], curve.begin, curve.end, *radius, max_offset,
                      &edges[i]);
  }
  if (estimate_radius) {
    std::vector<double> radii;
    for (size_t i = 0; i < samples.points.size(); ++i) {
      const AxisPointFit fit =
          refiner.FitAxisPoint(samples.points[i], samples.tangents[i], *radius, true, edges[i]);
      if (fit.ok && fit.radius > 0.0) radii.push_back(fit.radius);
    }
    if (!radii.empty()) *radius = Median(radii);
  }
  std::vector<AxisPointFit> fits;
  for (size_t i = 0; i < samples.points.size(); ++i) {
    fits.push_back(
        refiner.FitAxisPoint(samples.points[i], samples.tangents[i], *radius, false, edges[i]));
  }
  return fits;
}

// What a pass of the refinement found, over its samples.
struct PassQuality {
  double residual_rms = 0.0;      // mm, over the edges used
  double refined_fraction = 0.0;  // of the samples
};

// The refined points smoothed again, parameterised by the samples' arc length.
Curve Resmooth(const Samples& samples, const std::vector<AxisPointFit>& fits,
               const ShapeOptions& options, PassQuality* quality) {
  Polyline points;
  std::vector<double> weights;
  double sum_sq = 0.0;
  int edges = 0;
  int refined = 0;
  for (size_t i = 0; i < fits.size(); ++i) {
    points.push_back(fits[i].ok ? fits[i].point : samples.points[i]);
    weights.push_back(fits[i].ok ? 1.0 : kUnrefinedWeight);
    if (!fits[i].ok) continue;
    sum_sq += fits[i].sum_sq_residual;
    edges += fits[i].edges_used;
    ++refined;
  }
  quality->residual_rms = edges > 0 ? std::sqrt(sum_sq / edges) : 0.0;
  quality->refined_fraction = static_cast<double>(refined) / std::max<size_t>(1, fits.size());
  Curve curve;
  curve.spline =
      SmoothingSpline::Fit(samples.arc, points, weights, options.knot_spacing, options.smoothing);
  curve.begin = samples.arc.front();
  curve.end = samples.arc.back();
  return curve;
}

// Moves the end of the curve to the centre of the tip's cap seen in the images.
void MoveTip(const SilhouetteRefiner& refiner, double radius, Curve* curve) {
  const Vec3 end = curve->spline.Point(curve->end);
  const Vec3 tangent = curve->spline.Derivative(curve->end);
  const std::optional<double> offset = refiner.FitTipOffset(end, tangent.normalized(), radius);
  if (!offset) return;
  curve->end = std::max(curve->begin + 1.0, curve->end + *offset / tangent.norm());
}

}  // namespace

std::string ShapeOptions::Validate() const {
  std::ostringstream error;
  const auto expect = [&error](bool ok, const char* key, const char* what, double got) {
    if (!ok && error.tellp() == 0) error << key << ": expected " << what << ", got " << got;
  };
  expect(tube_radius >= 0.0 && std::isfinite(tube_radius), "tube_radius", "a number >= 0",
         tube_radius);
  expect(output_spacing > 0.0 && output_spacing <= 2.0, "output_spacing", "a number in (0, 2]",
         output_spacing);
  expect(slice_width > 0.0 && slice_width <= 20.0, "slice_width", "a number in (0, 20]",
         slice_width);
  expect(smoothing >= 0.0 && smoothing <= 100.0, "smoothing", "a number in [0, 100]", smoothing);
  expect(knot_spacing >= 1.0 && knot_spacing <= 50.0, "knot_spacing", "a number in [1, 50]",
         knot_spacing);
  expect(curvature_window > 0.0 && curvature_window <= 100.0, "curvature_window",
         "a number in (0, 100]", curvature_window);
  expect(refine_iterations >= 0 && refine_iterations <= 20, "refine_iterations",
         "an integer in [0, 20]", refine_iterations);
  expect(max_base_distance > 0.0 && std::isfinite(max_base_distance), "max_base_distance",
         "a number > 0", max_base_distance);
  expect(min_marker_voxels >= 1, "min_marker_voxels", "an integer >= 1", min_marker_voxels);
  expect(band_width == 0.0 || (band_width >= 1.0 && band_width <= 30.0), "band_width",
         "0 (not known) or a number in [1, 30]", band_width);
  return error.str();
}

ShapeEstimator::ShapeEstimator(const Rig& rig, const ShapeOptions& options)
    : rig_(rig), options_(options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw std::invalid_argument("ShapeOptions: " + error);
  }
}

namespace {

// The body reached from the base, ordered and sliced; `error` when there is
// none worth measuring.
struct Body {
  std::string error;
  GeodesicBody geodesic;
  std::vector<BodySlice> slices;
  double hull_radius = 0.0;
};

Body FindBody(const VoxelCloud& cloud, const VoxelGraph& graph, const Vec3& base_point,
              const ShapeOptions& options) {
  Body body;
  const double voxel = cloud.grid.voxel_size;
  body.geodesic = FindGeodesicBodyByBlocks(cloud, graph, base_point, options.max_base_distance,
                                           kSeedMarginVoxels * voxel);
  if (!body.geodesic.error.empty()) {
    body.error = body.geodesic.error;
  } else if (body.geodesic.members.size() < kMinBodyVoxels) {
    body.error = "the body reached from the base has only " +
                 std::to_string(body.geodesic.members.size()) + " voxels";
  } else {
    body.slices = SliceByDistance(cloud, graph, body.geodesic, options.slice_width);
    if (body.slices.size() < kMinSlices) {
      body.error = "the body is too short: " + std::to_string(body.slices.size()) + " slices";
    } else {
      const double length = body.slices.back().distance - body.slices.front().distance + voxel;
      body.hull_radius = HullRadius(body.geodesic, voxel, length);
    }
  }
  return body;
}

// Refines the curve (and the radius, when unknown) against the silhouettes;
// returns the last pass's quality.
PassQuality RefineAgainstSilhouettes(const SilhouetteRefiner& refiner, const ShapeOptions& options,
                                     Curve* curve, double* radius) {
  PassQuality quality;
  for (int pass = 0; pass < options.refine_iterations; ++pass) {
    const Samples samples = SampleCurve(*curve, options.knot_spacing / kRefinedPointsPerKnot);
    const bool estimate_radius = pass == 0 && options.tube_radius <= 0.0;
    const std::vector<AxisPointFit> fits =
        FitSamples(refiner, *curve, samples, pass == 0, estimate_radius, radius);
    Curve refined = Resmooth(samples, fits, options, &quality);
    if (refined.spline.empty()) break;
    *curve = refined;
    MoveTip(refiner, *radius, curve);
  }
  return quality;
}

// The centreline, its arc length and curvature from the final curve.
void SampleCenterline(const Curve& curve, const ShapeOptions& options, ShapeEstimate* estimate) {
  std::vector<double> params;
  estimate->centerline =
      SampleByArcLength(curve.spline, curve.begin, curve.end, options.output_spacing, &params);
  estimate->arc_length = CumulativeArcLength(estimate->centerline);
  estimate->tip = estimate->centerline.back();
  estimate->length = estimate->arc_length.back();
  // Tangents from the spline itself, at the parameter of each arc length.
  const auto tangent = [&](double s) -> Vec3 {
    return curve.spline.Derivative(Interpolate(estimate->arc_length, params, s)).normalized();
  };
  estimate->curvature = CurvatureByTurningAngle(estimate->arc_length, estimate->length, tangent,
                                                options.curvature_window);
}

}  // namespace

ShapeEstimate ShapeEstimator::Estimate(const VoxelCloud& cloud,
                                       const std::vector<Silhouette>& silhouettes) const {
  if (const std::string error = CheckInputs(rig_, cloud, silhouettes); !error.empty()) {
    return Failure(error);
  }
  const VoxelGraph graph(cloud);
  const Body body = FindBody(cloud, graph, rig_.base_point, options_);
  if (!body.error.empty()) return Failure(body.error);
  Curve curve = InitialCurve(body.slices, cloud, graph, body.geodesic, options_, body.hull_radius);
  if (curve.spline.empty()) return Failure("no centreline fits the body's slices");

  ShapeEstimate estimate;
  estimate.tube_radius = options_.tube_radius > 0.0 ? options_.tube_radius : body.hull_radius;
  const bool refine = options_.refine_with_silhouettes && !silhouettes.empty();
  if (refine && options_.refine_iterations > 0) {
    const SilhouetteRefiner refiner(rig_, silhouettes);
    const PassQuality quality =
        RefineAgainstSilhouettes(refiner, options_, &curve, &estimate.tube_radius);
    if (quality.refined_fraction < kMinRefinedFraction) {
      return Failure("the silhouettes confirm only " +
                     std::to_string(static_cast<int>(100.0 * quality.refined_fraction)) +
                     "% of the centreline: the visual hull is not the tube's (too few cameras, "
                     "or cameras that face each other?)");
    }
    estimate.silhouette_residual_mm = quality.residual_rms;
  }
  SampleCenterline(curve, options_, &estimate);
  std::vector<MarkerOnCurve> markers =
      FindMarkers(cloud, graph, body.geodesic, estimate.centerline, estimate.arc_length,
                  options_.min_marker_voxels, kMarkerGapVoxels * cloud.grid.voxel_size);
  if (refine) {
    BandPrior prior;
    prior.width = options_.band_width;
    prior.seed_error = 2.0 * cloud.grid.voxel_size;
    LocateBandsInImages(rig_, silhouettes, estimate.centerline, estimate.arc_length,
                        estimate.tube_radius, prior, &markers);
  }
  for (const MarkerOnCurve& marker : markers) {
    estimate.markers.push_back(marker.point);
    estimate.marker_arc_length.push_back(marker.arc_length);
    estimate.marker_std.push_back(marker.std_mm);
  }
  estimate.valid = true;
  return estimate;
}

}  // namespace shapesense
