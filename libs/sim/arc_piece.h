#pragma once

// A circular arc (or a straight piece when the curvature is ~0) from `start`
// with unit tangent `tangent`, curving towards the unit `normal`: the piece
// the scene generators and the trajectory build their centrelines from.
#include <cmath>

#include "libs/geometry/types.h"

namespace shapesense {

struct ArcPiece {
  Vec3 start;
  Vec3 tangent;
  Vec3 normal;
  double curvature = 0.0;  // 1/mm, signed
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

}  // namespace shapesense
