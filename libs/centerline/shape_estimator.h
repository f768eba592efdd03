#pragma once

#include <string>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/carving/voxel_grid.h"
#include "libs/geometry/types.h"
#include "libs/silhouette/silhouette.h"

namespace shapesense {

struct ShapeOptions {
  // Tube radius, mm; 0 estimates it from the silhouettes (without them, the
  // visual hull's mean radius stands in, a little larger).
  double tube_radius = 0.0;
  // Spacing of the output centreline points, mm (≤ 2).
  double output_spacing = 1.0;
  // Width of the slices of the voxel body along the geodesic distance from
  // the base, mm.
  double slice_width = 1.0;
  // Smoothing of the centreline spline: a length, mm, below which a penalty
  // on the change of curvature smooths details away (larger is smoother; 0
  // leaves only the knots). It does not flatten arcs.
  double smoothing = 3.0;
  // Spacing of the spline's knots along the body, mm: the finest bend it can follow.
  double knot_spacing = 5.0;
  // Curvature at s is the turning angle between the tangents at s ± window/2
  // over window, mm (exact for arcs; longer is less noisy but blurs changes).
  double curvature_window = 10.0;
  // Refine the centreline against the silhouettes' sub-pixel edges.
  bool refine_with_silhouettes = true;
  // Passes of the refinement; the second re-fits with the tangents of the
  // first's result, more rarely help.
  int refine_iterations = 2;
  // Voxels farther than this from the base point cannot start the body, mm.
  double max_base_distance = 15.0;
  // A marker needs at least this many marker voxels.
  int min_marker_voxels = 3;
  // Width of the tape bands along the tube, mm (0: not known, bands of 1-12
  // mm are accepted). A band seen much wider or narrower in a view is
  // something else there (two bands merged, another part of the tube).
  double band_width = 0.0;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("tube_radius", tube_radius, "tube radius, mm (0: estimate from the silhouettes)");
    visit("output_spacing", output_spacing, "spacing of the output centreline points, mm (0-2]");
    visit("slice_width", slice_width, "slice width along the body, mm (0-20]");
    visit("smoothing", smoothing, "centreline spline smoothing length, mm (0-100)");
    visit("knot_spacing", knot_spacing, "spacing of the spline's knots, mm (1-50)");
    visit("curvature_window", curvature_window,
          "arc length over which curvature is measured, mm (0-100]");
    visit("refine_with_silhouettes", refine_with_silhouettes,
          "fit the centreline to sub-pixel silhouette edges");
    visit("refine_iterations", refine_iterations, "refinement iterations (0-20)");
    visit("max_base_distance", max_base_distance,
          "farthest voxel from the base point that can start the body, mm");
    visit("min_marker_voxels", min_marker_voxels, "smallest tape marker, voxels");
    visit("band_width", band_width,
          "width of the tape bands along the tube, mm (0: not known; else 1-30)");
  }
  std::string Validate() const;
};

// The measured shape, world frame, mm. When `valid` is false, `error` says why
// and the rest is empty.
struct ShapeEstimate {
  bool valid = false;
  std::string error;
  Polyline centerline;             // base → tip, at most output_spacing apart
  std::vector<double> arc_length;  // per centreline point, from the base, mm
  std::vector<double> curvature;   // per centreline point, 1/mm
  std::vector<Vec3> markers;       // tape centres on the centreline, base → tip
  std::vector<double> marker_arc_length;
  // Each marker's confidence: the standard error of its centre along the
  // tube, mm (markers.h). A band that could not be placed is missing.
  std::vector<double> marker_std;
  Vec3 tip = Vec3::Zero();   // distal end of the centreline
  double length = 0.0;       // mm
  double tube_radius = 0.0;  // used or estimated, mm
  // RMS distance, after the last refinement, of the edges' viewing rays from
  // the tube's surface around the refined axis points, mm (0 unrefined).
  double silhouette_residual_mm = 0.0;
};

// Centreline, curvature, markers and tip from a carved body.
//  1. Order the voxels by geodesic distance from the base through the body
//     (works for bends of any angle, unlike the reference's angle sort): a
//     bucket-queue Dijkstra with steps of 1, √2, √3 on blocks of 2×2×2
//     voxels, interpolated back to the voxels (block_geodesic.h). Voxels not
//     connected to the base are ignored.
//  2. Centroids of slices of equal geodesic distance → a smoothing spline
//     (smoothing_spline.h), from the workspace face that cuts the body at the
//     base to one hull radius short of its far end.
//  3. Refinement (silhouette_refiner.h): each edge of the tube in each image
//     back-projects to a viewing ray that grazes the tube, so it passes at the
//     tube radius from the axis; a small least-squares system per axis point
//     gives its displacement across the axis (and the radius, when unknown),
//     then the spline is fitted again. The tip is the centre of the sphere
//     that the ray through the silhouette's far end grazes. A body the
//     silhouettes do not bear out is refused.
//  4. Arc length, and curvature as turning angle over a window along the
//     spline (curve_measures.h); tape markers are clusters of marker voxels,
//     then placed from the tape's edges read along lines of the tube's
//     surface in every image, to a fraction of a pixel, and fused over the
//     views (markers.h); a band no view places is missing.
// Typical cost: about 0.7 ms for a 160 mm tube of 5-6k voxels seen by three
// cameras (Release, one core).
class ShapeEstimator {
 public:
  // Throws std::invalid_argument on options that fail validation.
  ShapeEstimator(const Rig& rig, const ShapeOptions& options);

  // `silhouettes` in the order of rig.cameras (may be empty: no refinement).
  ShapeEstimate Estimate(const VoxelCloud& cloud, const std::vector<Silhouette>& silhouettes) const;

 private:
  Rig rig_;
  ShapeOptions options_;
};

}  // namespace shapesense
