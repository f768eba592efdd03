#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace shapesense {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
// Rigid transform named for what it maps, e.g. cam_from_world * x_world = x_cam.
using Pose3 = Eigen::Isometry3d;
// Ordered 3-D points, mm.
using Polyline = std::vector<Vec3, Eigen::aligned_allocator<Vec3>>;

// The pose x -> R x + translation, R the rotation by `rotation_vector`
// (unit axis times angle, rad; OpenCV's rvec).
inline Pose3 PoseFromRotationVector(const Vec3& rotation_vector, const Vec3& translation) {
  Pose3 pose = Pose3::Identity();
  const double angle = rotation_vector.norm();
  if (angle > 0.0) {
    pose.linear() = Eigen::AngleAxisd(angle, rotation_vector / angle).toRotationMatrix();
  }
  pose.translation() = translation;
  return pose;
}

}  // namespace shapesense
