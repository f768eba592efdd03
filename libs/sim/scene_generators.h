#pragma once

#include <cstdint>

#include "libs/camera/camera.h"
#include "libs/sim/tube_scene.h"

namespace shapesense {

// Centrelines for test scenes, sampled every `spacing` mm, base first.

// Straight along `direction` for `straight_length`, then a circular arc of
// `arc_length` turning by `bend_angle` (rad) towards `bend_direction`
// (perpendicular to `direction`).
Polyline ArcCenterline(const Vec3& base, const Vec3& direction, const Vec3& bend_direction,
                       double straight_length, double arc_length, double bend_angle,
                       double spacing = 0.25);

// Two arcs bending in opposite senses (an S), with an optional twist of the
// second bending plane about the tangent (rad).
Polyline SCurveCenterline(const Vec3& base, const Vec3& direction, const Vec3& bend_direction,
                          double arc_length_each, double bend_angle_each, double twist,
                          double spacing = 0.25);

struct SyntheticRigOptions {
  int num_cameras = 3;
  int image_width = 640;
  int image_height = 480;
  double focal_px = 700.0;
  double distance = 450.0;        // camera centre to the workspace centre, mm
  double elevation_deg = 20.0;    // above the workspace's horizontal plane
  double workspace_half_size = 128.0;  // the carving volume is a cube, mm
  bool distortion = true;         // realistic radial and tangential coefficients
  uint32_t seed = 0;              // jitters positions, aims and lens parameters
};

// Cameras spread around the vertical (z) axis, looking at the workspace centre
// (the origin); base point at the centre of the workspace's bottom face.
Rig MakeSyntheticRig(const SyntheticRigOptions& options);

// A random scene inside the rig's workspace: an arc of up to `max_bend` rad or
// an S-curve, from the base, radius 2.5-4 mm, with `num_tapes` tape bands.
TubeScene RandomScene(const Rig& rig, uint32_t seed, double max_bend_rad, int num_tapes = 3);

}  // namespace shapesense
