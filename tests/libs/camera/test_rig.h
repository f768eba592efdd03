#pragma once

#include "libs/camera/camera.h"

namespace shapesense::testing {

// A camera 500 mm from the origin looking at it, with a lens distortion of
// the size real machine-vision lenses have.
inline Camera DistortedCamera(const std::string& name, double azimuth_rad) {
  Camera camera;
  camera.name = name;
  camera.width = 640;
  camera.height = 480;
  camera.camera_matrix << 800, 0, 322.5, 0, 805, 238.0, 0, 0, 1;
  camera.distortion = {-0.12, 0.05, 0.001, -0.0015, 0.01};
  const Vec3 center(500 * std::cos(azimuth_rad), 500 * std::sin(azimuth_rad), 40.0);
  const Vec3 forward = (-center).normalized();
  const Vec3 right = forward.cross(Vec3::UnitZ()).normalized();
  const Vec3 down = forward.cross(right);
  Mat3 world_from_cam;
  world_from_cam << right, down, forward;
  camera.cam_from_world.linear() = world_from_cam.transpose();
  camera.cam_from_world.translation() = -world_from_cam.transpose() * center;
  return camera;
}

}  // namespace shapesense::testing
