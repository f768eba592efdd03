#include <algorithm>
#include <cmath>

#include "libs/sim/scene_generators.h"

namespace shapesense {
namespace {

// A circular arc (or a straight piece when the curvature is ~0) from `start`
// with unit tangent `tangent`, curving towards the unit `normal`.
struct ArcPiece {
  Vec3 start;
  Vec3 tangent;
  Vec3 normal;
  double curvature = 0.0;  // 1/mm
  double length = 0.0;     // mm

  Vec3 PointAt(double s) const {
    if (std::abs(curvature) < 1e-12) return start + s * tangent;
    const double angle = curvature * s;
    return start + (std::sin(angle) / curvature) * tangent +
           ((1.0 - std::cos(angle)) / curvature) * normal;
  }
  Vec3 TangentAt(double s) const {
    const double angle = curvature * s;
    return std::cos(angle) * tangent + std::sin(angle) * normal;
  }
  // The direction of curvature at s (the normal turned with the tangent).
  Vec3 NormalAt(double s) const {
    const double angle = curvature * s;
    return -std::sin(angle) * tangent + std::cos(angle) * normal;
  }
  Vec3 End() const { return PointAt(length); }
};

// The unit component of `v` perpendicular to the unit `axis`; any
// perpendicular when `v` is (nearly) parallel to it.
Vec3 PerpendicularUnit(const Vec3& axis, const Vec3& v) {
  Vec3 perpendicular = v - v.dot(axis) * axis;
  if (perpendicular.norm() < 1e-9) perpendicular = axis.unitOrthogonal();
  return perpendicular.normalized();
}

ArcPiece MakePiece(const Vec3& start, const Vec3& tangent, const Vec3& normal, double length,
                   double angle) {
  return {start, tangent, normal, length > 0.0 ? angle / length : 0.0, std::max(0.0, length)};
}

// Samples consecutive pieces uniformly in arc length, with steps of at most `spacing`.
Polyline SamplePieces(const std::vector<ArcPiece>& pieces, double spacing) {
  double total = 0.0;
  for (const ArcPiece& piece : pieces) total += piece.length;
  const int steps = std::max(1, static_cast<int>(std::ceil(total / spacing - 1e-9)));
  Polyline points;
  points.reserve(static_cast<size_t>(steps) + 1);
  size_t index = 0;
  double piece_begin = 0.0;
  for (int k = 0; k <= steps; ++k) {
    const double s = total * k / steps;
    while (index + 1 < pieces.size() && s > piece_begin + pieces[index].length) {
      piece_begin += pieces[index].length;
      ++index;
    }
    points.push_back(pieces[index].PointAt(std::min(s - piece_begin, pieces[index].length)));
  }
  return points;
}

}  // namespace

Polyline ArcCenterline(const Vec3& base, const Vec3& direction, const Vec3& bend_direction,
                       double straight_length, double arc_length, double bend_angle,
                       double spacing) {
  const Vec3 tangent = direction.normalized();
  const Vec3 normal = PerpendicularUnit(tangent, bend_direction);
  const ArcPiece straight = MakePiece(base, tangent, normal, straight_length, 0.0);
  const ArcPiece arc = MakePiece(straight.End(), tangent, normal, arc_length, bend_angle);
  return SamplePieces({straight, arc}, spacing);
}

Polyline SCurveCenterline(const Vec3& base, const Vec3& direction, const Vec3& bend_direction,
                          double arc_length_each, double bend_angle_each, double twist,
                          double spacing) {
  const Vec3 tangent = direction.normalized();
  const ArcPiece first = MakePiece(base, tangent, PerpendicularUnit(tangent, bend_direction),
                                   arc_length_each, bend_angle_each);
  // The second arc bends the other way, its plane turned by `twist` about the tangent.
  const Vec3 joint_tangent = first.TangentAt(first.length);
  const Vec3 reverse = Eigen::AngleAxisd(twist, joint_tangent) * -first.NormalAt(first.length);
  const ArcPiece second =
      MakePiece(first.End(), joint_tangent, reverse, arc_length_each, bend_angle_each);
  return SamplePieces({first, second}, spacing);
}

}  // namespace shapesense
