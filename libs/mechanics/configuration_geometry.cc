#include "libs/mechanics/configuration_geometry.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "libs/mechanics/arc_geometry.h"

namespace shapesense {
namespace {

// Rotation of the section's frame after s mm of arc: exp([kappa] s).
Mat3 ArcRotation(double kappa_x, double kappa_z, double s) {
  const Vec3 rotation_vector = s * Vec3(kappa_x, 0.0, kappa_z);
  const double angle = rotation_vector.norm();
  if (angle == 0.0) return Mat3::Identity();
  return Eigen::AngleAxisd(angle, rotation_vector / angle).toRotationMatrix();
}

int Steps(double length, double spacing) {
  return std::max(1, static_cast<int>(std::ceil(length / spacing - 1e-9)));
}

}  // namespace

SectionLengths CompressedLengths(const Configuration& q, const SectionLengths& rest) {
  return {rest.proximal * (1.0 - q(kStrainProximal)), rest.distal * (1.0 - q(kStrainDistal))};
}

Pose3 BaseFromDistalStart(const Configuration& q, const SectionLengths& rest) {
  Pose3 pose = Pose3::Identity();
  pose.translation() = Vec3(0.0, CompressedLengths(q, rest).proximal, 0.0);
  return pose;
}

Pose3 BaseFromDistalPoint(const Configuration& q, const SectionLengths& rest, double s) {
  s = std::clamp(s, 0.0, CompressedLengths(q, rest).distal);
  Pose3 start_from_point = Pose3::Identity();
  start_from_point.linear() = ArcRotation(q(kKappaX), q(kKappaZ), s);
  start_from_point.translation() = ArcPoint(q(kKappaX), q(kKappaZ), s);
  return BaseFromDistalStart(q, rest) * start_from_point;
}

Pose3 BaseFromTip(const Configuration& q, const SectionLengths& rest) {
  return BaseFromDistalPoint(q, rest, CompressedLengths(q, rest).distal);
}

Polyline DistalCenterline(const Configuration& q, const SectionLengths& rest, double spacing) {
  assert(spacing > 0.0);
  const double length = CompressedLengths(q, rest).distal;
  const Vec3 start = BaseFromDistalStart(q, rest).translation();
  const int steps = Steps(length, spacing);
  Polyline points;
  points.reserve(static_cast<size_t>(steps) + 1);
  for (int k = 0; k <= steps; ++k) {
    const double s = length * k / steps;
    points.push_back(start + ArcPoint(q(kKappaX), q(kKappaZ), s));
  }
  return points;
}

Polyline CenterlineFromConfiguration(const Configuration& q, const SectionLengths& rest,
                                     double spacing) {
  assert(spacing > 0.0);
  const double proximal = CompressedLengths(q, rest).proximal;
  const int steps = Steps(proximal, spacing);
  Polyline points;
  for (int k = 0; k < steps; ++k) points.push_back(Vec3(0.0, proximal * k / steps, 0.0));
  const Polyline distal = DistalCenterline(q, rest, spacing);
  points.insert(points.end(), distal.begin(), distal.end());
  return points;
}

}  // namespace shapesense
