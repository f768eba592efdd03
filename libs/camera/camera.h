#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "libs/geometry/types.h"

namespace shapesense {

// Pinhole camera with OpenCV's 5-coefficient distortion (k1 k2 p1 p2 k3) and
// extrinsics x_cam = cam_from_world * x_world. Pixel (0, 0) is the centre of
// the top-left pixel, as in OpenCV.
struct Camera {
  std::string name;
  int width = 0;
  int height = 0;
  Mat3 camera_matrix = Mat3::Identity();
  std::array<double, 5> distortion{};  // k1 k2 p1 p2 k3
  Pose3 cam_from_world = Pose3::Identity();

  // Camera centre in the world frame, mm.
  Vec3 Center() const;

  // Pixel of a world point, with distortion; nullopt when the point is not in
  // front of the camera.
  std::optional<Vec2> Project(const Vec3& world) const;

  // Normalised image coordinates (x/z, y/z) → distorted pixel.
  Vec2 DistortAndScale(const Vec2& normalized) const;

  // Pixel → normalised undistorted coordinates (x/z, y/z); iterative inverse
  // of the distortion, exact to ~1e-10 for the distortions of real lenses.
  Vec2 UnscaleAndUndistort(const Vec2& pixel) const;

  // Unit direction, in the world frame, of the viewing ray through a pixel.
  Vec3 RayDirectionWorld(const Vec2& pixel) const;

  bool InImage(const Vec2& pixel) const;

  // Empty when the model is usable; otherwise what is wrong with it.
  std::string Validate() const;
};

// A calibrated multi-camera rig and the volume it carves.
struct Rig {
  std::vector<Camera> cameras;
  Vec3 workspace_min = Vec3::Zero();  // mm, world frame
  Vec3 workspace_max = Vec3::Zero();  // mm, world frame
  Vec3 base_point = Vec3::Zero();     // where the manipulator enters, mm

  const Camera* Find(const std::string& name) const;
  std::string Validate() const;
};

}  // namespace shapesense
