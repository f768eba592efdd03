#pragma once

// Tubes with known centrelines for the centreline tests, independent of the
// renderer and the carver: analytic voxels (a voxel is occupied when its
// centre is within the radius plus an inflation of the axis, as the visual
// hull is a little larger than the tube), and anti-aliased silhouettes cast
// exactly (each pixel's ray against the union of spheres along the axis).

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/carving/voxel_grid.h"
#include "libs/geometry/polyline.h"
#include "libs/silhouette/silhouette.h"

namespace shapesense::testing {

inline double Uniform(std::mt19937& rng, double low, double high) {
  return std::uniform_real_distribution<double>(low, high)(rng);
}

// Appends a circular arc of `length` turning by `angle` towards `bend`
// (perpendicular to the current direction) to `points`, every `step` mm.
inline void AppendArc(Polyline* points, Vec3* direction, const Vec3& bend, double length,
                      double angle, double step = 0.25) {
  const Vec3 start = points->back();
  const Vec3 d0 = *direction;
  const Vec3 n = (bend - bend.dot(d0) * d0).normalized();
  const int steps = std::max(1, static_cast<int>(std::ceil(length / step)));
  for (int k = 1; k <= steps; ++k) {
    const double s = length * k / steps;
    if (std::abs(angle) < 1e-9) {
      points->push_back(start + s * d0);
      continue;
    }
    const double radius = length / angle;
    const double a = s / radius;
    points->push_back(start + radius * std::sin(a) * d0 + radius * (1.0 - std::cos(a)) * n);
  }
  const double a = angle;
  *direction = (std::cos(a) * d0 + std::sin(a) * n).normalized();
}

// Straight for `straight`, then an arc of `arc_length` bending by `angle`.
inline Polyline ArcTube(const Vec3& base, const Vec3& direction, const Vec3& bend, double straight,
                        double arc_length, double angle) {
  Polyline points = {base};
  Vec3 d = direction.normalized();
  if (straight > 0.0) AppendArc(&points, &d, bend, straight, 0.0);
  AppendArc(&points, &d, bend, arc_length, angle);
  return points;
}

// Two arcs bending in opposite senses.
inline Polyline SCurveTube(const Vec3& base, const Vec3& direction, const Vec3& bend,
                           double straight, double arc_each, double angle_each) {
  Polyline points = ArcTube(base, direction, bend, straight, arc_each, angle_each);
  Vec3 d = (points.back() - points[points.size() - 2]).normalized();
  AppendArc(&points, &d, -bend, arc_each, angle_each);
  return points;
}

// A helix about a vertical axis, `turns` × 360° of radius `radius` and
// `pitch` mm per turn, after a straight start along its first tangent.
inline Polyline SpiralTube(const Vec3& base, double straight, double radius, double pitch,
                           double turns, Vec3* axis_point = nullptr) {
  const double lift = pitch / (2.0 * std::numbers::pi);
  const Vec3 tangent = Vec3(0.0, radius, lift).normalized();
  Polyline points = {base};
  Vec3 direction = tangent;
  AppendArc(&points, &direction, Vec3::UnitX(), straight, 0.0);
  const Vec3 center = points.back() - Vec3(radius, 0.0, 0.0);
  if (axis_point != nullptr) *axis_point = center;
  const double step = 0.25 / std::hypot(radius, lift);
  for (double a = step; a <= 2.0 * std::numbers::pi * turns; a += step) {
    points.push_back(center + Vec3(radius * std::cos(a), radius * std::sin(a), lift * a));
  }
  return points;
}

struct Tape {
  double center = 0.0;  // arc length from the base, mm
  double width = 4.0;
};

// A cube of 1 mm voxels around the origin, `half` mm each way.
inline Rig FixtureRig(int num_cameras, double half = 100.0, double distance = 450.0,
                      double elevation_deg = 20.0) {
  Rig rig;
  for (int k = 0; k < num_cameras; ++k) {
    Camera camera;
    camera.name = "cam" + std::to_string(k);
    camera.width = 640;
    camera.height = 480;
    camera.camera_matrix << 700, 0, 321.3, 0, 702, 238.6, 0, 0, 1;
    camera.distortion = {-0.10, 0.04, 0.0008, -0.0011, 0.0};
    const double azimuth = 2.0 * std::numbers::pi * k / num_cameras + 0.3;
    const double elevation = elevation_deg * std::numbers::pi / 180.0;
    const Vec3 center =
        distance * Vec3(std::cos(elevation) * std::cos(azimuth),
                        std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    const Vec3 forward = (-center).normalized();
    const Vec3 right = forward.cross(Vec3::UnitZ()).normalized();
    const Vec3 down = forward.cross(right);
    Mat3 world_from_cam;
    world_from_cam << right, down, forward;
    camera.cam_from_world.linear() = world_from_cam.transpose();
    camera.cam_from_world.translation() = -world_from_cam.transpose() * center;
    rig.cameras.push_back(camera);
  }
  rig.workspace_min = Vec3::Constant(-half);
  rig.workspace_max = Vec3::Constant(half);
  rig.base_point = Vec3(0, 0, -half);
  return rig;
}

inline VoxelGrid FixtureGrid(const Rig& rig, double voxel_size = 1.0) {
  VoxelGrid grid;
  grid.voxel_size = voxel_size;
  grid.origin = rig.workspace_min + Vec3::Constant(0.5 * voxel_size);
  for (int axis = 0; axis < 3; ++axis) {
    grid.dims[static_cast<size_t>(axis)] = static_cast<int>(
        std::lround((rig.workspace_max[axis] - rig.workspace_min[axis]) / voxel_size));
  }
  return grid;
}

// The axis continued straight behind the base by `lead_in` mm (the mount the
// tube comes from), and its arc length from the base (negative behind it).
inline Polyline WithLeadIn(const Polyline& axis, double lead_in, std::vector<double>* arc) {
  const Vec3 back = (axis[0] - axis[1]).normalized();
  Polyline points;
  arc->clear();
  for (double s = lead_in; s > 0.0; s -= 0.25) {
    points.push_back(axis[0] + s * back);
    arc->push_back(-s);
  }
  const std::vector<double> body_arc = CumulativeArcLength(axis);
  for (size_t i = 0; i < axis.size(); ++i) {
    points.push_back(axis[i]);
    arc->push_back(body_arc[i]);
  }
  return points;
}

inline bool OnTape(const std::vector<Tape>& tapes, double s) {
  return std::any_of(tapes.begin(), tapes.end(),
                     [s](const Tape& t) { return std::abs(s - t.center) <= 0.5 * t.width; });
}

// Voxels whose centre lies within radius + inflation of the axis (with its
// lead-in); a voxel is a marker when the closest axis point is on a tape.
inline VoxelCloud VoxelizeTube(const VoxelGrid& grid, const Polyline& axis, double radius,
                               double inflation, const std::vector<Tape>& tapes = {}) {
  std::vector<double> arc;
  const Polyline points = WithLeadIn(axis, 20.0, &arc);
  const double reach = radius + inflation;
  struct Nearest {
    double distance;
    double arc;
  };
  std::unordered_map<int64_t, Nearest> hit;
  for (size_t k = 0; k < points.size(); ++k) {
    const Vec3 c = (points[k] - grid.origin) / grid.voxel_size;
    const int span = static_cast<int>(std::ceil(reach / grid.voxel_size)) + 1;
    for (int z = static_cast<int>(c.z()) - span; z <= static_cast<int>(c.z()) + span; ++z) {
      for (int y = static_cast<int>(c.y()) - span; y <= static_cast<int>(c.y()) + span; ++y) {
        for (int x = static_cast<int>(c.x()) - span; x <= static_cast<int>(c.x()) + span; ++x) {
          if (x < 0 || y < 0 || z < 0 || x >= grid.dims[0] || y >= grid.dims[1] ||
              z >= grid.dims[2]) {
            continue;
          }
          const double d = (grid.Center(x, y, z) - points[k]).norm();
          if (d > reach) continue;
          auto [it, inserted] = hit.try_emplace(grid.Index(x, y, z), Nearest{d, arc[k]});
          if (!inserted && d < it->second.distance) it->second = {d, arc[k]};
        }
      }
    }
  }
  std::vector<std::pair<int64_t, Nearest>> sorted(hit.begin(), hit.end());
  std::sort(sorted.begin(), sorted.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  VoxelCloud cloud;
  cloud.grid = grid;
  for (const auto& [index, nearest] : sorted) {
    cloud.voxels.push_back(static_cast<int32_t>(index));
    cloud.labels.push_back(OnTape(tapes, nearest.arc) ? kLabelMarker : kLabelBody);
  }
  return cloud;
}

struct SilhouetteStyle {
  double contrast = 110.0;  // difference of the body over the backdrop
  double backdrop = 0.0;    // difference of the backdrop (a shadow raises it)
  double noise_sigma = 0.0;
  double threshold = 30.0;  // mask where the difference exceeds it
};

// The silhouette of the tube (with its lead-in) in one camera: the
// difference is the body's contrast times the pixel's coverage, the coverage
// from the signed distance of the pixel's ray to the tube's surface.
inline Silhouette RenderSilhouette(const Camera& camera, const Polyline& axis, double radius,
                                   const std::vector<Tape>& tapes, const SilhouetteStyle& style,
                                   std::mt19937& rng) {
  std::vector<double> arc;
  const Polyline points = WithLeadIn(axis, 60.0, &arc);
  const int w = camera.width;
  const int h = camera.height;
  std::vector<float> edge(static_cast<size_t>(w) * h, 1e9f);
  std::vector<float> edge_arc(edge.size(), 0.0f);
  std::vector<float> entry_depth(edge.size(), 1e9f);
  std::vector<Vec3> rays(edge.size(), Vec3::Zero());
  const Vec3 c0 = camera.Center();
  const double f = camera.camera_matrix(0, 0);
  for (size_t k = 0; k < points.size(); ++k) {
    const std::optional<Vec2> q = camera.Project(points[k]);
    if (!q) continue;
    const double depth = (camera.cam_from_world * points[k]).z();
    const double reach = 1.3 * f * radius / depth + 3.0;
    const int x0 = std::max(0, static_cast<int>(q->x() - reach));
    const int x1 = std::min(w - 1, static_cast<int>(q->x() + reach) + 1);
    const int y0 = std::max(0, static_cast<int>(q->y() - reach));
    const int y1 = std::min(h - 1, static_cast<int>(q->y() + reach) + 1);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const size_t i = static_cast<size_t>(y) * w + x;
        if (rays[i].isZero()) rays[i] = camera.RayDirectionWorld(Vec2(x, y));
        const Vec3 to_center = points[k] - c0;
        const double distance = to_center.cross(rays[i]).norm();
        const double px = (distance - radius) * f / depth;
        edge[i] = std::min(edge[i], static_cast<float>(px));
        // The label is the tape's where the ray enters the tube: the
        // sphere it meets first.
        if (distance < radius) {
          const double entry =
              to_center.dot(rays[i]) - std::sqrt(radius * radius - distance * distance);
          if (entry < entry_depth[i]) {
            entry_depth[i] = static_cast<float>(entry);
            edge_arc[i] = static_cast<float>(arc[k]);
          }
        }
      }
    }
  }
  Silhouette s;
  s.mask = cv::Mat::zeros(h, w, CV_8U);
  s.labels = cv::Mat::zeros(h, w, CV_8U);
  s.difference = cv::Mat::zeros(h, w, CV_8U);
  std::normal_distribution<double> noise(0.0, style.noise_sigma);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const double coverage = std::clamp(0.5 - edge[i], 0.0, 1.0);
      double value = style.backdrop + coverage * (style.contrast - style.backdrop);
      if (style.noise_sigma > 0.0) value += noise(rng);
      value = std::clamp(std::abs(value), 0.0, 255.0);
      s.difference.at<uint8_t>(y, x) = static_cast<uint8_t>(std::lround(value));
      if (value > style.threshold && coverage > 0.0) {
        s.mask.at<uint8_t>(y, x) = 255;
        // Edge pixels the rays only graze take the body's label.
        const bool tape = entry_depth[i] < 1e8f && OnTape(tapes, edge_arc[i]);
        s.labels.at<uint8_t>(y, x) = tape ? kLabelMarker : kLabelBody;
      }
    }
  }
  return s;
}

inline std::vector<Silhouette> RenderSilhouettes(const Rig& rig, const Polyline& axis,
                                                 double radius, const std::vector<Tape>& tapes,
                                                 const SilhouetteStyle& style, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<Silhouette> out;
  for (const Camera& camera : rig.cameras) {
    out.push_back(RenderSilhouette(camera, axis, radius, tapes, style, rng));
  }
  return out;
}

// Distance both ways between an estimate and the truth, mm: the RMS of the
// estimate's points to the true polyline, and of the true points to the
// estimate (so a short estimate cannot look good); the larger of the two.
inline double TwoWayRms(const Polyline& estimate, const Polyline& truth) {
  return std::max(RmsDistanceToPolyline(estimate, truth), RmsDistanceToPolyline(truth, estimate));
}

}  // namespace shapesense::testing
