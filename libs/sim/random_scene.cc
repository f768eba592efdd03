#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "libs/geometry/polyline.h"
#include "libs/sim/scene_generators.h"

namespace shapesense {
namespace {

constexpr int kMaxDraws = 500;
constexpr double kWorkspaceMarginMm = 5.0;
constexpr double kImageMarginPx = 8.0;
// Parts of the tube farther apart along it than this many radii must keep a
// gap of at least kMinGapRadii radii between their surfaces.
constexpr double kNeighbourhoodRadii = 8.0;
constexpr double kMinGapRadii = 3.0;

double Uniform(std::mt19937& rng, double low, double high) {
  return std::uniform_real_distribution<double>(low, high)(rng);
}

// Tape bands evenly spread over the middle of the body, jittered, never overlapping.
std::vector<TapeBand> DrawTapes(double length, int count, std::mt19937& rng) {
  std::vector<TapeBand> tapes;
  const double first = 0.12 * length;
  const double pitch = 0.76 * length / std::max(1, count);
  for (int k = 0; k < count; ++k) {
    TapeBand tape;
    tape.width = Uniform(rng, 3.0, 6.0);
    tape.center_arc_length = first + (k + 0.5 + Uniform(rng, -0.15, 0.15)) * pitch;
    tapes.push_back(tape);
  }
  return tapes;
}

// An arc or (one time in two) an S-curve, in a random bending plane.
TubeScene DrawScene(const Rig& rig, double max_bend_rad, int num_tapes, std::mt19937& rng) {
  TubeScene scene;
  const double length = Uniform(rng, 120.0, 200.0);
  scene.radius = Uniform(rng, 2.5, 4.0);
  const double plane = Uniform(rng, 0.0, 2.0 * std::numbers::pi);
  const Vec3 bend_direction(std::cos(plane), std::sin(plane), 0.0);
  const bool s_curve = Uniform(rng, 0.0, 1.0) < 0.5;
  const double bend = max_bend_rad * Uniform(rng, s_curve ? 0.3 : 0.0, 1.0);
  const double twist = Uniform(rng, -0.6, 0.6);
  scene.centerline =
      s_curve ? SCurveCenterline(rig.base_point, Vec3::UnitZ(), bend_direction, 0.5 * length, bend,
                                 twist)
              : ArcCenterline(rig.base_point, Vec3::UnitZ(), bend_direction, 0.0, length, bend);
  scene.tapes = DrawTapes(length, num_tapes, rng);
  return scene;
}

// The body and its radius stay 5 mm inside the side and top faces; the tube
// enters through the bottom face at the base (along +z) and is above it by
// the margin from twice the margin's arc length on.
bool InsideWorkspace(const Rig& rig, const TubeScene& scene) {
  const double margin = kWorkspaceMarginMm + scene.radius;
  const std::vector<double> arc = CumulativeArcLength(scene.centerline);
  for (size_t i = 0; i < scene.centerline.size(); ++i) {
    const Vec3& p = scene.centerline[i];
    for (int axis = 0; axis < 2; ++axis) {
      if (p[axis] < rig.workspace_min[axis] + margin) return false;
      if (p[axis] > rig.workspace_max[axis] - margin) return false;
    }
    if (p.z() > rig.workspace_max.z() - margin) return false;
    if (p.z() < rig.workspace_min.z() + std::min(0.5 * arc[i], margin)) return false;
  }
  return true;
}

// Every point of the body, widened by its projected radius, projects at least
// 8 px inside every image.
bool InsideImages(const Rig& rig, const TubeScene& scene) {
  for (const Camera& camera : rig.cameras) {
    for (const Vec3& p : scene.centerline) {
      const double depth = (camera.cam_from_world * p).z();
      const auto pixel = camera.Project(p);
      if (!pixel) return false;
      // 10% more than the pinhole radius covers the lens's local magnification.
      const double margin =
          kImageMarginPx + 1.1 * scene.radius * camera.camera_matrix(0, 0) / depth;
      if (pixel->x() < margin || pixel->x() > camera.width - 1 - margin) return false;
      if (pixel->y() < margin || pixel->y() > camera.height - 1 - margin) return false;
    }
  }
  return true;
}

bool KeepsClearOfItself(const TubeScene& scene) {
  const Polyline points = ResampleUniform(scene.centerline, 1.0);
  const double neighbourhood = kNeighbourhoodRadii * scene.radius;
  const double min_distance = (2.0 + kMinGapRadii) * scene.radius;
  for (size_t i = 0; i < points.size(); ++i) {
    // Samples are 1 mm apart, so index differences are arc-length differences.
    for (size_t j = i + static_cast<size_t>(std::ceil(neighbourhood)); j < points.size(); ++j) {
      if ((points[i] - points[j]).norm() < min_distance) return false;
    }
  }
  return true;
}

}  // namespace

TubeScene RandomScene(const Rig& rig, uint32_t seed, double max_bend_rad, int num_tapes) {
  std::mt19937 rng(seed);
  for (int draw = 0; draw < kMaxDraws; ++draw) {
    TubeScene scene = DrawScene(rig, max_bend_rad, num_tapes, rng);
    if (InsideWorkspace(rig, scene) && KeepsClearOfItself(scene) && InsideImages(rig, scene)) {
      return scene;
    }
  }
  throw std::invalid_argument(
      "RandomScene: no tube fits the rig's workspace and images; the workspace or the cameras' "
      "fields of view are too small for tubes of 120-200 mm");
}

}  // namespace shapesense
