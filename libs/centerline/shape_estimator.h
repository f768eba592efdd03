#pragma once

#include <string>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/carving/voxel_grid.h"
#include "libs/geometry/types.h"
#include "libs/silhouette/silhouette.h"

namespace shapesense {

struct ShapeOptions {
  // Tube radius, mm; 0 estimates it from the silhouettes.
  double tube_radius = 0.0;
  // Spacing of the output centreline points, mm (≤ 2).
  double output_spacing = 1.0;
  // Width of the slices of the voxel body along the geodesic distance from
  // the base, mm.
  double slice_width = 1.0;
  // Smoothing of the centreline spline (larger is smoother; 0 interpolates).
  double smoothing = 1.0;
  // Refine the centreline against the silhouettes' sub-pixel edges.
  bool refine_with_silhouettes = true;
  int refine_iterations = 3;
  // Voxels farther than this from the base point cannot start the body, mm.
  double max_base_distance = 15.0;
  // A marker needs at least this many marker voxels.
  int min_marker_voxels = 3;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("tube_radius", tube_radius, "tube radius, mm (0: estimate from the silhouettes)");
    visit("output_spacing", output_spacing, "spacing of the output centreline points, mm (0-2]");
    visit("slice_width", slice_width, "slice width along the body, mm (> 0)");
    visit("smoothing", smoothing, "centreline spline smoothing (>= 0)");
    visit("refine_with_silhouettes", refine_with_silhouettes, "fit the centreline to sub-pixel silhouette edges");
    visit("refine_iterations", refine_iterations, "refinement iterations (0-20)");
    visit("max_base_distance", max_base_distance, "farthest voxel from the base point that can start the body, mm");
    visit("min_marker_voxels", min_marker_voxels, "smallest tape marker, voxels");
  }
  std::string Validate() const;
};

// The measured shape, world frame, mm. When `valid` is false, `error` says why
// and the rest is empty.
struct ShapeEstimate {
  bool valid = false;
  std::string error;
  Polyline centerline;              // base → tip, at most output_spacing apart
  std::vector<double> arc_length;   // per centreline point, from the base, mm
  std::vector<double> curvature;    // per centreline point, 1/mm
  std::vector<Vec3> markers;        // tape centres on the centreline, base → tip
  std::vector<double> marker_arc_length;
  Vec3 tip = Vec3::Zero();          // distal end of the centreline
  double length = 0.0;              // mm
  double tube_radius = 0.0;         // used or estimated, mm
  double silhouette_residual_mm = 0.0;  // RMS of the refinement's edge residuals
};

// Centreline, curvature, markers and tip from a carved body.
//  1. Order the voxels by geodesic distance from the base through the body
//     (works for bends of any angle, unlike the reference's angle sort).
//  2. Centroids of slices of equal geodesic distance → a smoothing spline.
//  3. Refinement: each edge of the tube in each image back-projects to a
//     plane tangent to the tube; the axis lies at the tube radius from all of
//     them (sub-voxel, from sub-pixel edges). The tip comes from the tangent
//     plane at the silhouette's far end.
//  4. Arc length and curvature along the spline; tape markers are clusters of
//     marker voxels, projected onto the centreline.
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
