#include "libs/sim/trajectory.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>

#include "libs/core/error.h"
#include "libs/sim/arc_piece.h"

namespace shapesense {
namespace {

TrajectoryPose PoseOf(const TrajectoryKeyframe& keyframe) {
  const bool arc = keyframe.shape == "arc";
  return {keyframe.length, arc ? keyframe.bend_angle / 2 : keyframe.bend_angle,
          arc ? keyframe.bend_angle / 2 : -keyframe.bend_angle, keyframe.bend_plane,
          arc ? 0.0 : keyframe.twist};
}

TrajectoryPose Blend(const TrajectoryPose& a, const TrajectoryPose& b, double w) {
  auto mix = [w](double x, double y) { return x + w * (y - x); };
  return {mix(a.length, b.length), mix(a.first_bend, b.first_bend),
          mix(a.second_bend, b.second_bend), mix(a.bend_plane, b.bend_plane),
          mix(a.twist, b.twist)};
}

Polyline Centerline(const Vec3& base, const TrajectoryPose& pose, double spacing) {
  const double half = pose.length / 2;
  const Vec3 bend(std::cos(pose.bend_plane), std::sin(pose.bend_plane), 0.0);
  const ArcPiece first{base, Vec3::UnitZ(), bend, pose.first_bend / half, half};
  const Vec3 joint_tangent = first.TangentAt(half);
  const Vec3 second_normal = Eigen::AngleAxisd(pose.twist, joint_tangent) * first.NormalAt(half);
  const ArcPiece second{first.PointAt(half), joint_tangent, second_normal, pose.second_bend / half,
                        half};
  const int steps = std::max(2, static_cast<int>(std::ceil(pose.length / spacing - 1e-9)));
  Polyline points;
  points.reserve(static_cast<size_t>(steps) + 1);
  for (int k = 0; k <= steps; ++k) {
    const double s = pose.length * k / steps;
    points.push_back(s <= half ? first.PointAt(s) : second.PointAt(s - half));
  }
  return points;
}

}  // namespace

std::string TrajectoryKeyframe::Validate() const {
  if (!(time >= 0.0 && std::isfinite(time))) return Expected("time", "a time >= 0, s", time);
  if (shape != "arc" && shape != "s_curve") return "shape: expected arc or s_curve, got " + shape;
  if (!(length >= 10.0 && length <= 1000.0)) return Expected("length", "10-1000 mm", length);
  if (!(std::abs(bend_angle) <= 2 * std::numbers::pi)) {
    return Expected("bend_angle", "an angle within +-2 pi rad", bend_angle);
  }
  if (!std::isfinite(bend_plane)) return Expected("bend_plane", "a finite angle, rad", bend_plane);
  if (!std::isfinite(twist)) return Expected("twist", "a finite angle, rad", twist);
  return "";
}

std::string TrajectoryTape::Validate() const {
  if (!(position >= 0.0 && position <= 1.0)) return Expected("position", "0-1", position);
  if (!(width > 0.0 && width < 1000.0)) return Expected("width", "a positive width, mm", width);
  return "";
}

namespace {

std::string Mm(double value) {
  std::ostringstream out;
  out << value << " mm";
  return out.str();
}

// "" when the bands fit on a tube `length` mm long, base → tip and apart;
// else what does not.
std::string TapesFit(const std::vector<TrajectoryTape>& tapes, double length) {
  double total = 0.0;
  for (const TrajectoryTape& tape : tapes) total += tape.width;
  if (total > length) {
    return "tapes: " + std::to_string(tapes.size()) + " bands need " + Mm(total) +
           " of tube, the shortest tube of the motion is " + Mm(length) +
           ": more bands than the tube can carry";
  }
  for (size_t i = 0; i < tapes.size(); ++i) {
    const std::string key = "tapes[" + std::to_string(i) + "]";
    const double center = tapes[i].position * length;
    if (center - 0.5 * tapes[i].width < 0.0 || center + 0.5 * tapes[i].width > length) {
      return key + ": a band " + Mm(tapes[i].width) + " wide centred " + Mm(center) +
             " from the base runs off the shortest tube of the motion (" + Mm(length) + ")";
    }
    if (i == 0) continue;
    const double gap = center - tapes[i - 1].position * length;
    const double half_widths = 0.5 * (tapes[i].width + tapes[i - 1].width);
    if (!(gap > half_widths)) {
      return key + ": " + Mm(gap) +
             " from the band before it on the shortest tube of the motion (" + Mm(length) +
             "), the bands " + Mm(half_widths) +
             " wide on average: bands wider than the spacing between them, or out of order "
             "(base → tip)";
    }
  }
  return "";
}

}  // namespace

std::vector<TrajectoryKeyframe> DefaultKeyframes() {
  return {{0.0, "arc", 160.0, 0.0, 0.0, 0.0},
          {2.0, "arc", 160.0, 1.6, 0.0, 0.0},
          {4.0, "s_curve", 160.0, 0.9, 0.8, 0.3},
          {6.0, "arc", 160.0, 1.4, 2.6, 0.0}};
}

std::vector<TrajectoryKeyframe> TrajectoryOptions::Keyframes() const {
  return keyframes.empty() ? DefaultKeyframes() : keyframes;
}

std::string TrajectoryOptions::Validate() const {
  for (size_t i = 0; i < keyframes.size(); ++i) {
    const std::string key = "keyframes[" + std::to_string(i) + "].";
    if (const std::string error = keyframes[i].Validate(); !error.empty()) return key + error;
    if (i > 0 && !(keyframes[i].time > keyframes[i - 1].time)) {
      return Expected(key + "time", "a time after the previous keyframe's", keyframes[i].time);
    }
  }
  if (!(loop_period > Keyframes().back().time && std::isfinite(loop_period))) {
    return Expected("loop_period", "a period longer than the last keyframe's time, s", loop_period);
  }
  if (!(tube_radius >= 0.5 && tube_radius <= 20.0)) {
    return Expected("tube_radius", "0.5-20 mm", tube_radius);
  }
  if (!(lead_in_length >= 0.0 && lead_in_length <= 500.0)) {
    return Expected("lead_in_length", "0-500 mm", lead_in_length);
  }
  for (size_t i = 0; i < tapes.size(); ++i) {
    if (const std::string error = tapes[i].Validate(); !error.empty()) {
      return "tapes[" + std::to_string(i) + "]." + error;
    }
  }
  double shortest = std::numeric_limits<double>::infinity();
  for (const TrajectoryKeyframe& key : Keyframes()) shortest = std::min(shortest, key.length);
  if (std::string error = TapesFit(tapes, shortest); !error.empty()) return error;
  if (!(spacing >= 0.05 && spacing <= 0.5)) return Expected("spacing", "0.05-0.5 mm", spacing);
  if (const std::string error = render.Validate(); !error.empty()) return "render." + error;
  return "";
}

TrajectoryPose PoseAt(const TrajectoryOptions& options, double t_seconds) {
  const std::vector<TrajectoryKeyframe> keys = options.Keyframes();
  double t = std::fmod(t_seconds, options.loop_period);
  if (t < 0.0) t += options.loop_period;
  if (t < keys.front().time) {
    // Between the last keyframe of the previous loop and the first.
    const double span = keys.front().time + options.loop_period - keys.back().time;
    const double w = (t + options.loop_period - keys.back().time) / span;
    return Blend(PoseOf(keys.back()), PoseOf(keys.front()), w);
  }
  size_t i = 0;
  while (i + 1 < keys.size() && keys[i + 1].time <= t) ++i;
  const TrajectoryKeyframe& next = i + 1 < keys.size() ? keys[i + 1] : keys.front();
  const double next_time = i + 1 < keys.size() ? next.time : next.time + options.loop_period;
  return Blend(PoseOf(keys[i]), PoseOf(next), (t - keys[i].time) / (next_time - keys[i].time));
}

TubeScene SceneOf(const TrajectoryOptions& options, const Rig& rig, const TrajectoryPose& pose) {
  TubeScene scene;
  scene.centerline = Centerline(rig.base_point, pose, options.spacing);
  scene.radius = options.tube_radius;
  scene.lead_in_length = options.lead_in_length;
  for (const TrajectoryTape& tape : options.tapes) {
    scene.tapes.push_back(TapeBand{tape.position * pose.length, tape.width, {30, 30, 200}});
  }
  return scene;
}

TubeScene SceneAt(const TrajectoryOptions& options, const Rig& rig, double t_seconds) {
  return SceneOf(options, rig, PoseAt(options, t_seconds));
}

double CurvatureAt(const TrajectoryPose& pose, double arc_length) {
  const double half = pose.length / 2;
  return std::abs(arc_length <= half ? pose.first_bend : pose.second_bend) / half;
}

}  // namespace shapesense
