#pragma once

#include <optional>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/centerline/smoothing_spline.h"
#include "libs/geometry/types.h"
#include "libs/silhouette/silhouette.h"

namespace shapesense {

// What one outline edge says about the axis: the edge pixel's viewing ray
// grazes the tube, so it passes at exactly the tube radius from the axis. The
// ray passes closest to the current axis at `distance`, in the direction
// `normal` (unit, from the ray towards the axis); moving the axis there by δ
// changes that distance by normal·δ, so the edge asks for
//   normal·δ = radius − distance.
struct EdgeConstraint {
  Vec3 normal;
  double distance = 0.0;
};

// The refinement of one axis point against the edges of its outline.
struct AxisPointFit {
  bool ok = false;
  Vec3 point = Vec3::Zero();
  double radius = 0.0;  // estimated or as given
  int edges_used = 0;
  double sum_sq_residual = 0.0;  // mm², over the edges used
};

// Sub-voxel centreline from the silhouettes' sub-pixel edges.
//
// The tube is the envelope of spheres of its radius centred on the axis (a
// canal surface, hemispherical tip included). Each outline edge seen by a
// camera back-projects to a viewing ray tangent to the tube, hence at the tube
// radius from the axis where it passes closest to it. For a straight tube that
// is the classic tangent plane through the camera centre, parallel to the
// axis; taking the closest approach instead also holds where a camera sees a
// bend obliquely and the outline comes from a cross-section millimetres away
// from the one walked from. With the edges of several cameras, the
// displacement of an axis point across its tangent is the least squares
// solution of a small linear system (and the radius too, if unknown).
class SilhouetteRefiner {
 public:
  // `silhouettes` in the order of rig.cameras; the references must outlive
  // the refiner.
  SilhouetteRefiner(const Rig& rig, const std::vector<Silhouette>& silhouettes);

  // The edges of the outline around the axis point at parameter `u` of
  // `axis` (a curve parameterised by arc length, valid on [begin, end]): in
  // each camera, walking from the point's image across the projected axis
  // both ways, at most about twice the projected radius. Edges that are not
  // found (out of the image, or the outline there is too wide: another part
  // of the tube overlaps) are left out, and so are edges whose ray passes
  // farther than `max_offset` mm from `radius` off the axis.
  void FindEdges(const SmoothingSpline& axis, double u, double begin, double end, double radius,
                 double max_offset, std::vector<EdgeConstraint>* edges) const;

  // The axis point in the plane through `p` normal to `t` that best meets the
  // edges (least squares); with `estimate_radius` the radius is a third
  // unknown. Edges whose residual stands out are dropped one at a time. Fails
  // when too few edges remain or they do not fix the point.
  AxisPointFit FitAxisPoint(const Vec3& p, const Vec3& t, double radius, bool estimate_radius,
                            const std::vector<EdgeConstraint>& edges) const;

  // Offset λ along `t` from `end` to the centre of the tube's hemispherical
  // tip, `end` + λ t. In each camera the walk along the projected axis from
  // `end` reaches the outline of the cap; that edge's viewing ray is tangent
  // to the cap's sphere, whose centre on the axis line is therefore `radius`
  // from the ray. A camera that sees another part of the tube over the end
  // (its outline there is too wide) is left out; the others are combined,
  // those that agree with the median weighted by how sideways they see the
  // axis. nullopt when no camera sees the tip.
  std::optional<double> FitTipOffset(const Vec3& end, const Vec3& t, double radius) const;

 private:
  struct View {
    const Camera* camera;
    const Silhouette* silhouette;
    Vec3 center;
    double focal_px;
  };
  // The camera's view of an axis point: its pixel, the unit image direction
  // of the axis there, and the projection linearised about it, which turns
  // pixels a few tens of px away into viewing rays (the lens distortion
  // bends little over that distance: the error is far below 1e-3 px).
  struct AxisView {
    Vec2 pixel;
    Vec2 along;
    Vec2 normalized;                      // undistorted (x/z, y/z) of the point
    Eigen::Matrix2d pixel_to_normalized;  // inverse Jacobian of the projection
  };
  // False when the camera sees the axis end-on or the point behind it.
  bool ViewAxis(const View& view, const Vec3& p, const Vec3& t, AxisView* out) const;
  Vec3 RayThrough(const View& view, const AxisView& axis, const Vec2& pixel) const;
  // λ as one camera sees it, and its weight.
  std::optional<double> TipOffsetInView(const View& view, const Vec3& end, const Vec3& t,
                                        double radius, double* weight) const;
  // Whether the outline across the axis at p has the tube's width.
  bool OutlineIsOwn(const View& view, const Vec3& p, const Vec3& t, double radius) const;
  // The tube's radius at p in the image, px.
  double RadiusPx(const View& view, const Vec3& p, double radius) const;
  static int MaxSteps(double radius_px, double extra_px);

  std::vector<View> views_;
};

}  // namespace shapesense
