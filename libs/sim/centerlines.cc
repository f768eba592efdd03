#include <algorithm>
#include <cmath>

#include "libs/sim/arc_piece.h"
#include "libs/sim/scene_generators.h"

namespace shapesense {
namespace {

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
