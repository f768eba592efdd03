#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <random>

#include "libs/camera/camera.h"
#include "libs/geometry/polyline.h"
#include "libs/sim/tube_scene.h"

namespace shapesense::testing {

inline Vec3 RandomUnit(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  return Vec3(normal(rng), normal(rng), normal(rng)).normalized();
}

// A unit vector perpendicular to the unit `axis`, at `angle` about it.
inline Vec3 PerpendicularAt(const Vec3& axis, double angle) {
  const Vec3 first = axis.unitOrthogonal();
  const Vec3 second = axis.cross(first);
  return std::cos(angle) * first + std::sin(angle) * second;
}

// Unit tangent of the centreline at arc length s.
inline Vec3 TangentAt(const Polyline& line, const std::vector<double>& arc, double s) {
  const double step = 0.5;
  const double low = std::max(0.0, s - step);
  const double high = std::min(arc.back(), s + step);
  return (PointAtArcLength(line, arc, high) - PointAtArcLength(line, arc, low)).normalized();
}

// The tube's whole axis as the renderer should draw it: lead-in then body,
// sampled every `spacing` mm (independent of the renderer's own code).
inline Polyline DenseAxis(const TubeScene& scene, double spacing) {
  Polyline axis;
  const Vec3 base = scene.centerline.front();
  const Vec3 back = -(scene.centerline[1] - base).normalized();
  for (double s = scene.lead_in_length; s > 0.0; s -= spacing) axis.push_back(base + s * back);
  const Polyline body = ResampleUniform(scene.centerline, spacing);
  axis.insert(axis.end(), body.begin(), body.end());
  return axis;
}

// Distance from the viewing ray of a pixel to the nearest of the points.
inline double RayDistanceToPoints(const Camera& camera, const Vec2& pixel, const Polyline& points) {
  const Vec3 origin = camera.Center();
  const Vec3 direction = camera.RayDirectionWorld(pixel);
  double best = std::numeric_limits<double>::infinity();
  for (const Vec3& p : points) {
    const Vec3 offset = p - origin;
    best = std::min(best, (offset - offset.dot(direction) * direction).squaredNorm());
  }
  return std::sqrt(best);
}

// Whether any pixel within `reach` px (Chebyshev) of the pixel nearest to
// `pixel` is set in the mask.
inline bool MaskNear(const cv::Mat& mask, const Vec2& pixel, int reach) {
  const int u = static_cast<int>(std::lround(pixel.x()));
  const int v = static_cast<int>(std::lround(pixel.y()));
  for (int dv = -reach; dv <= reach; ++dv) {
    for (int du = -reach; du <= reach; ++du) {
      const int x = u + du;
      const int y = v + dv;
      if (x >= 0 && y >= 0 && x < mask.cols && y < mask.rows && mask.at<uint8_t>(y, x)) {
        return true;
      }
    }
  }
  return false;
}

}  // namespace shapesense::testing
