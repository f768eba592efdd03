#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

#include "libs/sim/scene_generators.h"

namespace shapesense {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

double Uniform(std::mt19937& rng, double low, double high) {
  return std::uniform_real_distribution<double>(low, high)(rng);
}

// Right-handed camera rotation with z along `forward`, x to the image's right
// and y down, level with the world's horizontal before `roll` (rad).
Mat3 CamFromWorldRotation(const Vec3& forward, double roll) {
  const Vec3 right = forward.cross(Vec3::UnitZ()).normalized();
  const Vec3 down = forward.cross(right);
  Mat3 world_from_cam;
  world_from_cam << right, down, forward;
  return Eigen::AngleAxisd(roll, Vec3::UnitZ()).toRotationMatrix() * world_from_cam.transpose();
}

// A camera's pose: nominally on a circle around z at the given elevation,
// looking at the origin; jittered in distance and direction (about ±10% of the
// distance) and in aim (±2°).
Pose3 JitteredPose(const SyntheticRigOptions& options, int index, std::mt19937& rng) {
  const double azimuth =
      2.0 * std::numbers::pi * index / options.num_cameras + Uniform(rng, -0.1, 0.1);
  const double elevation = options.elevation_deg * kDegree + Uniform(rng, -0.05, 0.05);
  const double distance = options.distance * Uniform(rng, 0.9, 1.1);
  const Vec3 center = distance * Vec3(std::cos(elevation) * std::cos(azimuth),
                                      std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
  const Vec3 nominal_forward = -center.normalized();
  const Vec3 side = nominal_forward.cross(Vec3::UnitZ()).normalized();
  const Vec3 up = side.cross(nominal_forward);
  const Vec3 forward = (Eigen::AngleAxisd(Uniform(rng, -2.0, 2.0) * kDegree, side) *
                        Eigen::AngleAxisd(Uniform(rng, -2.0, 2.0) * kDegree, up) * nominal_forward)
                           .normalized();
  Pose3 cam_from_world = Pose3::Identity();
  cam_from_world.linear() = CamFromWorldRotation(forward, Uniform(rng, -2.0, 2.0) * kDegree);
  cam_from_world.translation() = -cam_from_world.linear() * center;
  return cam_from_world;
}

// Focal length ±3%, principal point ±8 px, and the distortion of a real
// machine-vision lens (mostly barrel). Every draw is made even without
// distortion, so a rig differs from its distortion-free twin only there.
void JitterLens(const SyntheticRigOptions& options, std::mt19937& rng, Camera* camera) {
  const double fx = options.focal_px * Uniform(rng, 0.97, 1.03);
  const double fy = fx * Uniform(rng, 0.998, 1.002);
  const double cx = 0.5 * (options.image_width - 1) + Uniform(rng, -8.0, 8.0);
  const double cy = 0.5 * (options.image_height - 1) + Uniform(rng, -8.0, 8.0);
  camera->camera_matrix << fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0;
  const std::array<double, 5> distortion = {
      Uniform(rng, -0.15, 0.05), Uniform(rng, -0.05, 0.05), Uniform(rng, -1.5e-3, 1.5e-3),
      Uniform(rng, -1.5e-3, 1.5e-3), Uniform(rng, -0.01, 0.01)};
  if (options.distortion) camera->distortion = distortion;
}

}  // namespace

std::string SyntheticRigOptions::Validate() const {
  std::ostringstream error;
  if (num_cameras < 1 || num_cameras > 16) {
    error << "num_cameras: expected 1-16, got " << num_cameras;
  } else if (image_width < 16 || image_width > 10000 || image_height < 16 || image_height > 10000) {
    error << "image_width, image_height: expected 16-10000 px, got " << image_width << " x "
          << image_height;
  } else if (!(focal_px > 0.0)) {
    error << "focal_px: expected a positive number, got " << focal_px;
  } else if (!(workspace_half_size > 0.0)) {
    error << "workspace_half_size: expected a positive number, got " << workspace_half_size;
  } else if (!(distance > std::sqrt(3.0) * workspace_half_size)) {
    error << "distance: expected more than the workspace's half diagonal ("
          << std::sqrt(3.0) * workspace_half_size << " mm), got " << distance;
  } else if (!(std::abs(elevation_deg) <= 80.0)) {
    error << "elevation_deg: expected -80 to 80, got " << elevation_deg;
  }
  return error.str();
}

Rig MakeSyntheticRig(const SyntheticRigOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw std::invalid_argument("MakeSyntheticRig: " + error);
  }
  std::mt19937 rng(options.seed);
  Rig rig;
  const double h = options.workspace_half_size;
  rig.workspace_min = Vec3::Constant(-h);
  rig.workspace_max = Vec3::Constant(h);
  rig.base_point = Vec3(0.0, 0.0, -h);
  for (int i = 0; i < options.num_cameras; ++i) {
    Camera camera;
    camera.name = "cam" + std::to_string(i);
    camera.width = options.image_width;
    camera.height = options.image_height;
    camera.cam_from_world = JitteredPose(options, i, rng);
    JitterLens(options, rng, &camera);
    rig.cameras.push_back(camera);
  }
  return rig;
}

}  // namespace shapesense
