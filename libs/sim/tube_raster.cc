#include "libs/sim/tube_raster.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "libs/geometry/polyline.h"

namespace shapesense {
namespace {

constexpr float kFar = std::numeric_limits<float>::infinity();
// Extra pixels around each projected box: the box edges are sampled, not
// solved, and anti-aliasing needs the half pixel outside the outline.
constexpr int kBoxPadPx = 3;

// One capsule in the camera frame, with the per-segment terms of the ray tests.
struct CameraSegment {
  Vec3 a;                // start
  Vec3 e;                // unit axis (any unit vector for a point)
  double length = 0.0;   // mm
  double a_sq = 0.0;     // |a|²
  double a_dot_e = 0.0;  // a·e
  double b_sq = 0.0;     // |b|²
  int32_t index = 0;     // segment number in the axis
};

CameraSegment ToCameraSegment(const Pose3& cam_from_world, const Vec3& a_world, const Vec3& b_world,
                              int32_t index) {
  CameraSegment segment;
  segment.a = cam_from_world * a_world;
  const Vec3 b = cam_from_world * b_world;
  segment.length = (b - segment.a).norm();
  segment.e = segment.length > 1e-12 ? Vec3((b - segment.a) / segment.length) : Vec3::UnitX();
  segment.a_sq = segment.a.squaredNorm();
  segment.a_dot_e = segment.a.dot(segment.e);
  segment.b_sq = b.squaredNorm();
  segment.index = index;
  return segment;
}

struct PixelBox {
  int u0, v0, u1, v1;  // inclusive
  bool empty() const { return u0 > u1 || v0 > v1; }
};

// Pixels the capsule can cover: its axis-aligned box projected without
// distortion (exact: a box projects inside the hull of its corners), clipped to
// the image, then distorted along the clipped rectangle's edges.
PixelBox ProjectedBox(const Camera& camera, const RayTable::Bounds& image,
                      const CameraSegment& segment, double radius) {
  const Vec3 b = segment.a + segment.length * segment.e;
  const Vec3 low = segment.a.cwiseMin(b).array() - radius;
  const Vec3 high = segment.a.cwiseMax(b).array() + radius;
  const PixelBox nothing{0, 0, -1, -1};
  if (high.z() <= 1e-6) return nothing;
  RayTable::Bounds box = image;
  if (low.z() > 1e-6) {
    box = {1e9, 1e9, -1e9, -1e9};
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3 p((corner & 1) ? high.x() : low.x(), (corner & 2) ? high.y() : low.y(),
                   (corner & 4) ? high.z() : low.z());
      box = {std::min(box.x0, p.x() / p.z()), std::min(box.y0, p.y() / p.z()),
             std::max(box.x1, p.x() / p.z()), std::max(box.y1, p.y() / p.z())};
    }
    box = {std::max(box.x0, image.x0), std::max(box.y0, image.y0), std::min(box.x1, image.x1),
           std::min(box.y1, image.y1)};
    if (box.x0 > box.x1 || box.y0 > box.y1) return nothing;
  }
  double u0 = 1e9, v0 = 1e9, u1 = -1e9, v1 = -1e9;
  constexpr int kSamples = 8;
  for (int k = 0; k <= kSamples; ++k) {
    const double x = box.x0 + (box.x1 - box.x0) * k / kSamples;
    const double y = box.y0 + (box.y1 - box.y0) * k / kSamples;
    for (const Vec2& n : {Vec2(x, box.y0), Vec2(x, box.y1), Vec2(box.x0, y), Vec2(box.x1, y)}) {
      const Vec2 pixel = camera.DistortAndScale(n);
      u0 = std::min(u0, pixel.x());
      v0 = std::min(v0, pixel.y());
      u1 = std::max(u1, pixel.x());
      v1 = std::max(v1, pixel.y());
    }
  }
  return {std::max(0, static_cast<int>(std::floor(u0)) - kBoxPadPx),
          std::max(0, static_cast<int>(std::floor(v0)) - kBoxPadPx),
          std::min(camera.width - 1, static_cast<int>(std::ceil(u1)) + kBoxPadPx),
          std::min(camera.height - 1, static_cast<int>(std::ceil(v1)) + kBoxPadPx)};
}

// Depth where a ray that passes within the radius enters the capsule (after
// Quilez's ray-capsule intersection, with a unit axis): the cylinder's wall,
// or the end sphere on the side the wall entry falls outside of.
double EntryDepth(const CameraSegment& s, double radius_sq, double d_dot_a, double d_dot_e,
                  double closest_depth) {
  const double wall_a = 1.0 - d_dot_e * d_dot_e;
  double wall_y = d_dot_e > 0.0 ? -1.0 : s.length + 1.0;  // ray along the axis: nearer cap
  if (wall_a > 1e-12) {
    const double wall_b = s.a_dot_e * d_dot_e - d_dot_a;
    const double wall_c = s.a_sq - s.a_dot_e * s.a_dot_e - radius_sq;
    const double h = wall_b * wall_b - wall_a * wall_c;
    if (h < 0.0) return closest_depth;  // grazing, lost to rounding
    const double t = (-wall_b - std::sqrt(h)) / wall_a;
    wall_y = t * d_dot_e - s.a_dot_e;
    if (wall_y >= 0.0 && wall_y <= s.length) return std::min(t, closest_depth);
  }
  const double d_dot_end = wall_y < 0.0 ? d_dot_a : d_dot_a + s.length * d_dot_e;
  const double end_sq = wall_y < 0.0 ? s.a_sq : s.b_sq;
  const double h = d_dot_end * d_dot_end - end_sq + radius_sq;
  if (h < 0.0) return closest_depth;
  return std::min(d_dot_end - std::sqrt(h), closest_depth);
}

void CastSegment(const CameraSegment& s, double radius, const PixelBox& box, const RayTable& rays,
                 TubeRaster* out) {
  const double radius_sq = radius * radius;
  for (int v = box.v0; v <= box.v1; ++v) {
    const size_t row = static_cast<size_t>(v) * rays.width;
    for (int u = box.u0; u <= box.u1; ++u) {
      const RayTable::Ray& ray = rays.rays[row + u];
      const double d_dot_a = ray.x * s.a.x() + ray.y * s.a.y() + ray.z * s.a.z();
      const double d_dot_e = ray.x * s.e.x() + ray.y * s.e.y() + ray.z * s.e.z();
      // Closest approach of the ray (a line through the origin) to the segment.
      const double denominator = 1.0 - d_dot_e * d_dot_e;
      double along = denominator > 1e-12 ? (d_dot_e * d_dot_a - s.a_dot_e) / denominator
                                         : (d_dot_e > 0.0 ? 0.0 : s.length);
      along = std::clamp(along, 0.0, s.length);
      const double closest_depth = d_dot_a + along * d_dot_e;
      const double axis_sq = s.a_sq + along * (2.0 * s.a_dot_e + along);
      const double distance_sq = std::max(0.0, axis_sq - closest_depth * closest_depth);
      PixelHit& hit = out->pixels[row + u];
      if (hit.edge_px > -0.5f) {
        const double edge = (std::sqrt(distance_sq) - radius) / (closest_depth * ray.pixel_size);
        if (edge < hit.edge_px) {
          hit.edge_px = static_cast<float>(edge);
          hit.near_segment = s.index;
        }
      }
      if (distance_sq > radius_sq) continue;
      const double depth = EntryDepth(s, radius_sq, d_dot_a, d_dot_e, closest_depth);
      if (depth < hit.depth) {
        hit.depth = static_cast<float>(depth);
        hit.hit_segment = s.index;
      }
    }
  }
}

// Closest point of the segment a-b to the point p, as a fraction of a→b.
double ClosestFraction(const Vec3& a, const Vec3& b, const Vec3& p) {
  const Vec3 ab = b - a;
  const double length_sq = ab.squaredNorm();
  return length_sq > 0.0 ? std::clamp((p - a).dot(ab) / length_sq, 0.0, 1.0) : 0.0;
}

}  // namespace

TubeAxis TubeAxisOf(const TubeScene& scene) {
  TubeAxis axis;
  axis.radius = scene.radius;
  const std::vector<double> arc = CumulativeArcLength(scene.centerline);
  if (scene.lead_in_length > 0.0 && scene.centerline.size() >= 2) {
    const Vec3 tangent = (scene.centerline[1] - scene.centerline[0]).normalized();
    axis.points.push_back(scene.centerline.front() - scene.lead_in_length * tangent);
    axis.arc_length.push_back(-scene.lead_in_length);
  }
  axis.points.insert(axis.points.end(), scene.centerline.begin(), scene.centerline.end());
  axis.arc_length.insert(axis.arc_length.end(), arc.begin(), arc.end());
  return axis;
}

void RasterizeTube(const Camera& camera, const RayTable& rays, const TubeAxis& axis,
                   TubeRaster* out) {
  out->width = camera.width;
  out->height = camera.height;
  out->pixels.assign(static_cast<size_t>(camera.width) * camera.height,
                     PixelHit{kFar, kFar, -1, -1});
  out->u0 = 0;
  out->v0 = 0;
  out->u1 = -1;
  out->v1 = -1;
  const RayTable::Bounds& image = rays.image_bounds;
  // A single point is a sphere: a segment of length zero.
  const size_t segments = axis.points.size() == 1 ? 1 : axis.points.size() - 1;
  for (size_t i = 0; i < segments && !axis.points.empty(); ++i) {
    const CameraSegment segment = ToCameraSegment(
        camera.cam_from_world, axis.points[i], axis.points[std::min(i + 1, axis.points.size() - 1)],
        static_cast<int32_t>(i));
    const PixelBox box = ProjectedBox(camera, image, segment, axis.radius);
    if (box.empty()) continue;
    CastSegment(segment, axis.radius, box, rays, out);
    const bool first = out->u0 > out->u1;
    out->u0 = first ? box.u0 : std::min(out->u0, box.u0);
    out->v0 = first ? box.v0 : std::min(out->v0, box.v0);
    out->u1 = first ? box.u1 : std::max(out->u1, box.u1);
    out->v1 = first ? box.v1 : std::max(out->v1, box.v1);
  }
}

SurfacePoint SurfaceAtDepth(const Vec3& a_cam, const Vec3& b_cam, double arc_a, double arc_b,
                            const Vec3& direction, double depth) {
  const Vec3 point = depth * direction;
  const double f = ClosestFraction(a_cam, b_cam, point);
  const Vec3 offset = point - (a_cam + f * (b_cam - a_cam));
  const double norm = offset.norm();
  return {norm > 0.0 ? Vec3(offset / norm) : Vec3(-direction), arc_a + f * (arc_b - arc_a)};
}

SurfacePoint SurfaceNearestRay(const Vec3& a_cam, const Vec3& b_cam, double arc_a, double arc_b,
                               const Vec3& direction) {
  // Closest approach of the line through the origin to the segment, by the
  // same convex minimisation as the raster (clamped line parameter).
  const double length = (b_cam - a_cam).norm();
  const Vec3 e = length > 1e-12 ? Vec3((b_cam - a_cam) / length) : Vec3::UnitX();
  const double d_dot_e = direction.dot(e);
  const double denominator = 1.0 - d_dot_e * d_dot_e;
  double along = denominator > 1e-12 ? (d_dot_e * direction.dot(a_cam) - a_cam.dot(e)) / denominator
                                     : (d_dot_e > 0.0 ? 0.0 : length);
  along = std::clamp(along, 0.0, length);
  const Vec3 axis_point = a_cam + along * e;
  const Vec3 offset = axis_point.dot(direction) * direction - axis_point;
  const double norm = offset.norm();
  const double fraction = length > 1e-12 ? along / length : 0.0;
  return {norm > 0.0 ? Vec3(offset / norm) : Vec3(-direction), arc_a + fraction * (arc_b - arc_a)};
}

}  // namespace shapesense
