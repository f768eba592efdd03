#include "libs/geometry/polyline.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace shapesense {

std::vector<double> CumulativeArcLength(const Polyline& points) {
  std::vector<double> arc(points.size(), 0.0);
  for (size_t i = 1; i < points.size(); ++i) {
    arc[i] = arc[i - 1] + (points[i] - points[i - 1]).norm();
  }
  return arc;
}

double PolylineLength(const Polyline& points) {
  const std::vector<double> arc = CumulativeArcLength(points);
  return arc.empty() ? 0.0 : arc.back();
}

Vec3 PointAtArcLength(const Polyline& points, const std::vector<double>& arc, double s) {
  assert(!points.empty() && points.size() == arc.size());
  if (s <= arc.front()) return points.front();
  if (s >= arc.back()) return points.back();
  const auto upper = std::upper_bound(arc.begin(), arc.end(), s);
  const size_t i = static_cast<size_t>(upper - arc.begin());
  const double span = arc[i] - arc[i - 1];
  const double t = span > 0.0 ? (s - arc[i - 1]) / span : 0.0;
  return points[i - 1] + t * (points[i] - points[i - 1]);
}

Polyline ResampleUniform(const Polyline& points, double spacing) {
  assert(points.size() >= 2 && spacing > 0.0);
  const std::vector<double> arc = CumulativeArcLength(points);
  const double length = arc.back();
  const int steps = std::max(1, static_cast<int>(std::ceil(length / spacing - 1e-9)));
  Polyline out;
  out.reserve(static_cast<size_t>(steps) + 1);
  for (int k = 0; k < steps; ++k) {
    out.push_back(PointAtArcLength(points, arc, std::min(length, k * spacing)));
  }
  out.push_back(points.back());
  return out;
}

ClosestPoint ClosestPointOnPolyline(const Polyline& points, const std::vector<double>& arc,
                                    const Vec3& query) {
  assert(!points.empty() && points.size() == arc.size());
  ClosestPoint best{points.front(), 0.0, (points.front() - query).norm()};
  for (size_t i = 1; i < points.size(); ++i) {
    const Vec3 segment = points[i] - points[i - 1];
    const double length_sq = segment.squaredNorm();
    const double t = length_sq > 0.0
                         ? std::clamp((query - points[i - 1]).dot(segment) / length_sq, 0.0, 1.0)
                         : 0.0;
    const Vec3 candidate = points[i - 1] + t * segment;
    const double distance = (candidate - query).norm();
    if (distance < best.distance) {
      best = {candidate, arc[i - 1] + t * (arc[i] - arc[i - 1]), distance};
    }
  }
  return best;
}

double RmsDistanceToPolyline(const Polyline& measured, const Polyline& truth) {
  if (measured.empty()) return std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> arc = CumulativeArcLength(truth);
  double sum_sq = 0.0;
  for (const Vec3& p : measured) {
    const double d = ClosestPointOnPolyline(truth, arc, p).distance;
    sum_sq += d * d;
  }
  return std::sqrt(sum_sq / static_cast<double>(measured.size()));
}

}  // namespace shapesense
