#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "libs/geometry/types.h"

namespace shapesense {

// Curvature at arc lengths `at` along a curve `length` mm long whose unit
// tangent at arc length s is tangent(s), 1/mm: the angle between the
// tangents at s − window/2 and s + window/2 over the arc length between them
// (at the ends the window slides inwards, staying within [margin,
// length − margin]). A circular arc of any radius gets exactly its 1/R, and
// only first derivatives are involved: noise is averaged over the window
// rather than differentiated twice.
template <class TangentAt>
std::vector<double> CurvatureByTurningAngle(const std::vector<double>& at, double length,
                                            TangentAt&& tangent, double window,
                                            double margin = 0.0) {
  std::vector<double> curvature(at.size(), 0.0);
  const double span = std::min(window, length - 2.0 * margin);
  if (span <= 1e-9) return curvature;
  const double highest = length - margin - span;
  for (size_t i = 0; i < at.size(); ++i) {
    const double s1 = std::clamp(at[i] - 0.5 * span, margin, std::max(margin, highest));
    const Vec3 t1 = tangent(s1);
    const Vec3 t2 = tangent(s1 + span);
    curvature[i] = std::atan2(t1.cross(t2).norm(), t1.dot(t2)) / span;
  }
  return curvature;
}

// Unit tangent of a polyline at arc length s: the chord from s − half_chord to
// s + half_chord (for a circular arc, exactly the tangent at s).
Vec3 ChordTangent(const Polyline& points, const std::vector<double>& arc, double s,
                  double half_chord);

// Curvature at each point of a polyline, with chords window/2 long as
// tangents (exact for arcs sampled finely compared with their radius).
std::vector<double> CurvatureByTurningAngle(const Polyline& points, const std::vector<double>& arc,
                                            double window);

}  // namespace shapesense
