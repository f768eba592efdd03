#pragma once

// Random rigs and silhouettes for the carving tests.

#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/silhouette/silhouette.h"
#include "tests/libs/camera/test_rig.h"

namespace shapesense::testing {

inline double Uniform(std::mt19937& rng, double low, double high) {
  return std::uniform_real_distribution<double>(low, high)(rng);
}

inline int UniformInt(std::mt19937& rng, int low, int high) {
  return std::uniform_int_distribution<int>(low, high)(rng);
}

inline bool Chance(std::mt19937& rng, double probability) {
  return Uniform(rng, 0, 1) < probability;
}

inline Vec3 RandomUnitVector(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  return Vec3(normal(rng), normal(rng), normal(rng)).normalized();
}

// A distorted camera looking at the origin from a random direction and
// distance, with a random image size (odd sizes included).
inline Camera RandomCamera(const std::string& name, double min_distance, double max_distance,
                           std::mt19937& rng) {
  Camera camera = DistortedCamera(name, Uniform(rng, 0, 6.3));
  // Rotating the world about the origin keeps the camera aimed at it.
  camera.cam_from_world =
      camera.cam_from_world * Eigen::AngleAxisd(Uniform(rng, 0, 3.1), RandomUnitVector(rng));
  // The centre lies on the optical axis through the origin; scaling the
  // translation slides the camera along it.
  const double distance = camera.cam_from_world.translation().norm();
  camera.cam_from_world.translation() *= Uniform(rng, min_distance, max_distance) / distance;
  const double scale = Uniform(rng, 0.4, 1.0);
  camera.width = static_cast<int>(640 * scale) | UniformInt(rng, 0, 1);
  camera.height = static_cast<int>(480 * scale) | UniformInt(rng, 0, 1);
  camera.camera_matrix.topRows(2) *= scale;
  return camera;
}

// A rig of random cameras over a box around the origin that is
// `voxels` × voxel_size on each axis, give or take half a voxel.
inline Rig RandomRig(int num_cameras, const std::array<int, 3>& voxels, double voxel_size,
                     double min_distance, std::mt19937& rng) {
  Rig rig;
  for (int c = 0; c < num_cameras; ++c) {
    rig.cameras.push_back(RandomCamera("cam" + std::to_string(c), min_distance, 700.0, rng));
  }
  for (int axis = 0; axis < 3; ++axis) {
    rig.workspace_min[axis] = -0.5 * voxels[axis] * voxel_size + Uniform(rng, -10, 10);
    // Not a whole number of voxels, so Covering must round up.
    rig.workspace_max[axis] = rig.workspace_min[axis] + (voxels[axis] - 0.5) * voxel_size;
  }
  return rig;
}

struct Ball {
  Vec3 centre;
  double radius;
};

// Draws a ball's projection as a disc (an approximation: the silhouettes of
// the equivalence tests need not be exact projections).
inline void DrawBall(const Camera& camera, const Ball& ball, cv::Mat* mask) {
  const Vec3 in_camera = camera.cam_from_world * ball.centre;
  const auto pixel = camera.Project(ball.centre);
  if (!pixel || in_camera.z() < ball.radius) return;
  const int radius = static_cast<int>(camera.camera_matrix(0, 0) * ball.radius / in_camera.z());
  cv::circle(*mask, cv::Point(static_cast<int>(pixel->x()), static_cast<int>(pixel->y())), radius,
             255, cv::FILLED);
}

// Draws a capsule between two balls of the same radius as a thick line.
inline void DrawCapsule(const Camera& camera, const Ball& a, const Vec3& b, cv::Mat* mask) {
  const auto pa = camera.Project(a.centre);
  const auto pb = camera.Project(b);
  const double depth = (camera.cam_from_world * a.centre).z();
  if (!pa || !pb || depth < a.radius) return;
  const int thickness =
      std::max(1, static_cast<int>(2 * camera.camera_matrix(0, 0) * a.radius / depth));
  cv::line(*mask, cv::Point(static_cast<int>(pa->x()), static_cast<int>(pa->y())),
           cv::Point(static_cast<int>(pb->x()), static_cast<int>(pb->y())), 255, thickness);
}

inline void DrawRandomEllipse(std::mt19937& rng, uint8_t value, cv::Mat* image) {
  // Centres up to a quarter of the size beyond the border, so blobs touch it.
  const cv::Point centre(UniformInt(rng, -image->cols / 4, image->cols * 5 / 4),
                         UniformInt(rng, -image->rows / 4, image->rows * 5 / 4));
  const cv::Size axes(UniformInt(rng, 1, std::max(1, image->cols / 3)),
                      UniformInt(rng, 1, std::max(1, image->rows / 3)));
  cv::ellipse(*image, centre, axes, Uniform(rng, 0, 180), 0, 360, value, cv::FILLED);
}

// Labels inside the mask: body, with marker blobs and scattered marker pixels.
inline cv::Mat RandomLabels(const cv::Mat& mask, std::mt19937& rng) {
  cv::Mat markers = cv::Mat::zeros(mask.size(), CV_8U);
  for (int i = UniformInt(rng, 0, 3); i > 0; --i) DrawRandomEllipse(rng, 255, &markers);
  cv::Mat noise(mask.size(), CV_8U);
  cv::randu(noise, 0, 100);
  markers.setTo(255, noise < 5);
  cv::Mat labels = cv::Mat::zeros(mask.size(), CV_8U);
  labels.setTo(kLabelBody, mask);
  labels.setTo(kLabelMarker, mask & markers);
  return labels;
}

// Silhouettes of random balls and capsules in the workspace, seen by every
// camera, each camera's image then spoiled at random: extra blobs, holes,
// or an image left empty or full.
inline std::vector<Silhouette> RandomSilhouettes(const Rig& rig, std::mt19937& rng) {
  std::vector<std::pair<Ball, Vec3>> shapes;
  const double extent = (rig.workspace_max - rig.workspace_min).minCoeff();
  for (int i = UniformInt(rng, 1, 4); i > 0; --i) {
    Ball ball{rig.workspace_min, Uniform(rng, 0.02, 0.25) * extent};
    for (int axis = 0; axis < 3; ++axis) {
      ball.centre[axis] = Uniform(rng, rig.workspace_min[axis], rig.workspace_max[axis]);
    }
    shapes.emplace_back(ball, ball.centre + RandomUnitVector(rng) * Uniform(rng, 0, extent / 2));
  }
  std::vector<Silhouette> silhouettes(rig.cameras.size());
  for (size_t c = 0; c < rig.cameras.size(); ++c) {
    const Camera& camera = rig.cameras[c];
    cv::Mat mask = cv::Mat::zeros(camera.height, camera.width, CV_8U);
    for (const auto& [ball, end] : shapes) {
      if (Chance(rng, 0.5))
        DrawBall(camera, ball, &mask);
      else
        DrawCapsule(camera, ball, end, &mask);
    }
    if (Chance(rng, 0.3)) DrawRandomEllipse(rng, 255, &mask);
    for (int i = UniformInt(rng, 0, 2); i > 0; --i) DrawRandomEllipse(rng, 0, &mask);
    if (Chance(rng, 0.08)) mask.setTo(0);
    if (Chance(rng, 0.08)) mask.setTo(255);
    silhouettes[c].labels = RandomLabels(mask, rng);
    silhouettes[c].mask = mask;
  }
  return silhouettes;
}

}  // namespace shapesense::testing
