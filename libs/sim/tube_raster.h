#pragma once

#include <cstdint>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/sim/ray_table.h"
#include "libs/sim/tube_scene.h"

// Internal to the renderer (renderer.cc); declared here for its tests.

namespace shapesense {

// The whole drawn tube as one polyline: the lead-in, then the measured body.
// The tube is the union of capsules (radius `radius`) around its segments.
struct TubeAxis {
  Polyline points;
  std::vector<double> arc_length;  // from the base, mm; negative along the lead-in
  double radius = 0.0;
};

TubeAxis TubeAxisOf(const TubeScene& scene);

// What a pixel-centre ray meets.
struct PixelHit {
  // Distance along the unit ray to where it enters the tube, mm; +inf: it misses.
  float depth;
  // Signed distance of the ray from the tube's surface, in pixels at the tube
  // (negative inside). Exact where it matters, within about one pixel of the
  // outline; elsewhere only its side of -0.5 and +0.5 is known.
  float edge_px;
  int32_t hit_segment;   // segment of the entry point, -1 when the ray misses
  int32_t near_segment;  // segment closest to a ray near the outline, -1 when none
};

// The pixel hits of one camera, row-major, reused between calls.
struct TubeRaster {
  int width = 0;
  int height = 0;
  std::vector<PixelHit> pixels;
  // The pixels any capsule may cover (the union of the boxes ray-cast),
  // inclusive; empty (u0 > u1) when the tube is out of view.
  int u0 = 0, v0 = 0, u1 = -1, v1 = -1;

  const PixelHit& at(int u, int v) const { return pixels[static_cast<size_t>(v) * width + u]; }
};

// Ray-casts every capsule over its projected bounding box, keeping per pixel
// the nearest entry and the closest approach.
void RasterizeTube(const Camera& camera, const RayTable& rays, const TubeAxis& axis,
                   TubeRaster* out);

// Where a ray (unit `direction` from the camera centre, camera frame) meets the
// surface of one segment's capsule at `depth`, or passes closest to it.
struct SurfacePoint {
  Vec3 normal;  // unit, camera frame
  double arc_length = 0.0;
};
SurfacePoint SurfaceAtDepth(const Vec3& a_cam, const Vec3& b_cam, double arc_a, double arc_b,
                            const Vec3& direction, double depth);
SurfacePoint SurfaceNearestRay(const Vec3& a_cam, const Vec3& b_cam, double arc_a, double arc_b,
                               const Vec3& direction);

}  // namespace shapesense
