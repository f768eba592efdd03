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

}  // namespace shapesense
