#include "libs/camera/camera.h"

#include <cmath>
#include <set>
#include <sstream>

namespace shapesense {

Vec3 Camera::Center() const { return cam_from_world.inverse().translation(); }

std::optional<Vec2> Camera::Project(const Vec3& world) const {
  const Vec3 cam = cam_from_world * world;
  if (cam.z() <= 1e-9) return std::nullopt;
  return DistortAndScale(Vec2(cam.x() / cam.z(), cam.y() / cam.z()));
}

Vec2 Camera::DistortAndScale(const Vec2& normalized) const {
  const auto [k1, k2, p1, p2, k3] = distortion;
  const double x = normalized.x();
  const double y = normalized.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
  const double yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
  const Mat3& k = camera_matrix;
  return {k(0, 0) * xd + k(0, 1) * yd + k(0, 2), k(1, 1) * yd + k(1, 2)};
}

Vec2 Camera::UnscaleAndUndistort(const Vec2& pixel) const {
  const Mat3& k = camera_matrix;
  const double yd = (pixel.y() - k(1, 2)) / k(1, 1);
  const double xd = (pixel.x() - k(0, 2) - k(0, 1) * yd) / k(0, 0);
  const Vec2 distorted(xd, yd);
  // Gauss-Newton on the forward model, starting from the distorted point;
  // converges in a few steps where the distortion is invertible.
  Vec2 guess = distorted;
  for (int iteration = 0; iteration < 20; ++iteration) {
    const auto [k1, k2, p1, p2, k3] = distortion;
    const double x = guess.x();
    const double y = guess.y();
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double dradial = k1 + r2 * (2.0 * k2 + 3.0 * r2 * k3);  // d radial / d r2
    const Vec2 model(x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
                     y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y);
    Eigen::Matrix2d jacobian;
    jacobian(0, 0) = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x;
    jacobian(0, 1) = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
    jacobian(1, 0) = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
    jacobian(1, 1) = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x;
    const Vec2 step = jacobian.partialPivLu().solve(distorted - model);
    guess += step;
    if (step.squaredNorm() < 1e-24) break;
  }
  return guess;
}

Vec3 Camera::RayDirectionWorld(const Vec2& pixel) const {
  const Vec2 n = UnscaleAndUndistort(pixel);
  return (cam_from_world.linear().transpose() * Vec3(n.x(), n.y(), 1.0)).normalized();
}

bool Camera::InImage(const Vec2& pixel) const {
  return pixel.x() >= -0.5 && pixel.y() >= -0.5 && pixel.x() < width - 0.5 &&
         pixel.y() < height - 0.5;
}

std::string Camera::Validate() const {
  std::ostringstream error;
  if (name.empty()) error << "camera has no name; ";
  if (width <= 0 || height <= 0) error << "image size must be positive; ";
  if (!(camera_matrix(0, 0) > 0.0) || !(camera_matrix(1, 1) > 0.0)) {
    error << "focal lengths (camera_matrix[0][0], [1][1]) must be positive; ";
  }
  if (camera_matrix(1, 0) != 0.0 || camera_matrix(2, 0) != 0.0 || camera_matrix(2, 1) != 0.0 ||
      camera_matrix(2, 2) != 1.0) {
    error << "camera_matrix must be upper triangular with [2][2] = 1; ";
  }
  const Mat3 r = cam_from_world.linear();
  if (!r.allFinite() || (r.transpose() * r - Mat3::Identity()).norm() > 1e-6 ||
      r.determinant() < 0.0) {
    error << "rotation must be a proper orthonormal matrix; ";
  }
  if (!cam_from_world.translation().allFinite()) error << "translation must be finite; ";
  for (const double c : distortion) {
    if (!std::isfinite(c)) error << "distortion_coefficients must be finite; ";
  }
  std::string text = error.str();
  if (text.size() >= 2) text.resize(text.size() - 2);
  return text;
}

const Camera* Rig::Find(const std::string& name) const {
  for (const Camera& camera : cameras) {
    if (camera.name == name) return &camera;
  }
  return nullptr;
}

std::string Rig::Validate() const {
  if (cameras.empty()) return "the rig has no cameras";
  std::set<std::string> names;
  for (const Camera& camera : cameras) {
    if (const std::string error = camera.Validate(); !error.empty()) {
      return "camera '" + camera.name + "': " + error;
    }
    if (!names.insert(camera.name).second) return "camera name '" + camera.name + "' repeats";
  }
  if (!(workspace_min.array() < workspace_max.array()).all()) {
    return "workspace_min must be below workspace_max on every axis";
  }
  return {};
}

}  // namespace shapesense
