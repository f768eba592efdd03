#include "libs/centerline/curve_measures.h"

#include "libs/geometry/polyline.h"

namespace shapesense {

Vec3 ChordTangent(const Polyline& points, const std::vector<double>& arc, double s,
                  double half_chord) {
  const Vec3 chord =
      PointAtArcLength(points, arc, s + half_chord) - PointAtArcLength(points, arc, s - half_chord);
  const double norm = chord.norm();
  return norm > 0.0 ? Vec3(chord / norm) : Vec3::Zero();
}

std::vector<double> CurvatureByTurningAngle(const Polyline& points, const std::vector<double>& arc,
                                            double window) {
  if (points.size() < 2) return std::vector<double>(points.size(), 0.0);
  const double half_chord = 0.25 * window;
  return CurvatureByTurningAngle(
      arc, arc.back(), [&](double s) { return ChordTangent(points, arc, s, half_chord); }, window,
      half_chord);
}

}  // namespace shapesense
