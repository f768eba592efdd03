#pragma once

// The virtual manipulator's scripted motion: keyframes of shapes (circular
// arcs and S-curves) interpolated in time and looping. Pure functions, no
// clock: the scene at time t is the same wherever it is computed (the
// rig-sim's fake cameras, the capture service's simulated backend, a test).
//
// Every shape is two circular pieces of half the length each, from the rig's
// base point up +z: an arc of bend angle b is two pieces of b/2 in one plane;
// an S-curve is +b then -b, the second plane twisted about the tangent.
// Interpolating the pieces' numbers keeps every in-between shape a smooth
// two-piece curve, so an arc can turn into an S-curve continuously.

#include <string>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/sim/tube_scene.h"

namespace shapesense {

struct TrajectoryKeyframe {
  double time = 0.0;          // s from the start of a loop
  std::string shape = "arc";  // arc | s_curve
  double length = 160.0;      // mm, base to tip
  double bend_angle = 0.0;    // rad; arc: total turning; s_curve: each half's turning
  double bend_plane = 0.0;    // rad, azimuth of the (first) bending direction about z, 0 = +x
  double twist = 0.0;         // rad, s_curve: second plane turned about the tangent

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("time", time, "time of this shape, s from the start of the loop (>= 0, increasing)");
    visit("shape", shape, "arc | s_curve");
    visit("length", length, "length from the base to the tip, mm (10-1000)");
    visit("bend_angle", bend_angle,
          "rad; arc: total bend; s_curve: bend of each half, in opposite senses (|.| <= 2 pi)");
    visit("bend_plane", bend_plane, "azimuth of the bending direction about +z, rad (0: +x)");
    visit("twist", twist, "s_curve: twist of the second bending plane about the tangent, rad");
  }
  std::string Validate() const;
};

// A band of tape at a fraction of the body's length (it moves with the body).
struct TrajectoryTape {
  double position = 0.5;  // fraction of the length from the base (0-1)
  double width = 4.0;     // mm

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("position", position, "centre of the band, fraction of the length from the base (0-1)");
    visit("width", width, "width of the band along the tube, mm (> 0)");
  }
  std::string Validate() const;
};

// The built-in motion, a slow sweep over 8 s: straight, bending 92 degrees
// one way, an S, bending 80 degrees another way (as config/rig_sim.yaml).
std::vector<TrajectoryKeyframe> DefaultKeyframes();

struct TrajectoryOptions {
  // Empty: DefaultKeyframes(). (Empty rather than filled in, so that the
  // keyframes of a file start from TrajectoryKeyframe's defaults.)
  std::vector<TrajectoryKeyframe> keyframes;
  // The motion repeats with this period: after the last keyframe it returns
  // to the first, reached again at loop_period.
  double loop_period = 8.0;
  double tube_radius = 3.0;      // mm
  double lead_in_length = 40.0;  // mm, straight, below the base (drawn, not measured)
  std::vector<TrajectoryTape> tapes = {{0.25, 4.0}, {0.55, 4.0}, {0.85, 4.0}};
  double spacing = 0.25;  // mm between centreline samples of the scene (<= 0.5)
  RenderOptions render;   // how the scene looks (libs/sim)

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("keyframes", keyframes,
          "shapes over time, interpolated linearly (none: the built-in sweep)");
    visit("loop_period", loop_period, "period of the loop, s (> the last keyframe's time)");
    visit("tube_radius", tube_radius, "radius of the tube, mm (0.5-20)");
    visit("lead_in_length", lead_in_length, "straight tube below the base, mm (0-500)");
    visit("tapes", tapes, "red bands of tape on the body");
    visit("spacing", spacing, "centreline sample spacing of the scene, mm (0.05-0.5)");
    visit("render", render, "how the scene is rendered (libs/sim RenderOptions)");
  }
  std::string Validate() const;
  // The keyframes in use: `keyframes`, or the defaults when it is empty.
  std::vector<TrajectoryKeyframe> Keyframes() const;
};

// The shape at one instant, as two circular pieces of length/2 each.
struct TrajectoryPose {
  double length = 0.0;       // mm
  double first_bend = 0.0;   // rad, turning of the first piece towards bend_plane
  double second_bend = 0.0;  // rad, of the second piece (negative: back)
  double bend_plane = 0.0;   // rad
  double twist = 0.0;        // rad, of the second piece's plane about the tangent
};

// The interpolated pose at t seconds (any t: the loop repeats, t < 0 too).
// Options must be valid (Validate() == "").
TrajectoryPose PoseAt(const TrajectoryOptions& options, double t_seconds);

// The scene of a pose: centreline from rig.base_point up +z, radius, lead-in, tapes.
TubeScene SceneOf(const TrajectoryOptions& options, const Rig& rig, const TrajectoryPose& pose);

// SceneOf(options, rig, PoseAt(options, t)).
TubeScene SceneAt(const TrajectoryOptions& options, const Rig& rig, double t_seconds);

// Curvature of the pose's centreline at an arc length from the base, 1/mm.
double CurvatureAt(const TrajectoryPose& pose, double arc_length);

}  // namespace shapesense
