#pragma once

#include <vector>

#include "libs/geometry/types.h"

namespace shapesense {

// Cumulative arc length at each point, starting at 0, mm.
std::vector<double> CumulativeArcLength(const Polyline& points);

// Total length of the polyline, mm.
double PolylineLength(const Polyline& points);

// Point at arc length s (clamped to [0, length]), linearly interpolated.
Vec3 PointAtArcLength(const Polyline& points, const std::vector<double>& arc, double s);

// Resamples at a uniform spacing (the last point is always kept, so the final
// step may be shorter). Requires at least two points.
Polyline ResampleUniform(const Polyline& points, double spacing);

struct ClosestPoint {
  Vec3 point;
  double arc_length = 0.0;  // along the polyline, mm
  double distance = 0.0;    // from the query, mm
};

// Closest point on the polyline (segments, not just vertices) to a query.
ClosestPoint ClosestPointOnPolyline(const Polyline& points, const std::vector<double>& arc,
                                    const Vec3& query);

// Root mean square of the distances from each point of `measured` to the
// polyline `truth` (segments), mm.
double RmsDistanceToPolyline(const Polyline& measured, const Polyline& truth);

}  // namespace shapesense
