#pragma once

#include <cstdint>
#include <string>

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

// A rig of evenly spread cameras around a cubic workspace. With the defaults
// the workspace centre is seen at about 0.64 mm per pixel, and every scene of
// RandomScene fits in every image.
struct SyntheticRigOptions {
  int num_cameras = 3;
  int image_width = 640;
  int image_height = 480;
  double focal_px = 700.0;
  double distance = 450.0;             // camera centre to the workspace centre, mm
  double elevation_deg = 20.0;         // above the workspace's horizontal plane
  double workspace_half_size = 128.0;  // the carving volume is a cube, mm
  bool distortion = true;              // realistic radial and tangential coefficients
  uint32_t seed = 0;                   // jitters positions, aims and lens parameters

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("num_cameras", num_cameras, "cameras around the workspace (1-16)");
    visit("image_width", image_width, "image width, px (16-10000)");
    visit("image_height", image_height, "image height, px (16-10000)");
    visit("focal_px", focal_px, "nominal focal length, px (> 0)");
    visit("distance", distance,
          "camera centre to the workspace centre, mm (> workspace diagonal / 2)");
    visit("elevation_deg", elevation_deg,
          "cameras' elevation above the horizontal, degrees (-80 to 80)");
    visit("workspace_half_size", workspace_half_size,
          "half the edge of the cubic workspace, mm (> 0)");
    visit("distortion", distortion, "give the lenses realistic distortion");
    visit("seed", seed, "jitter of camera poses and lenses");
  }
  std::string Validate() const;
};

// Cameras named cam0, cam1, ... spread evenly around the vertical (z) axis at
// the given elevation, looking at the workspace centre (the origin), each
// jittered by the seed: distance ±10%, azimuth ±0.1 rad, elevation ±0.05 rad,
// aim and roll ±2°, focal length ±3%, principal point ±8 px, and (with
// `distortion`) k1 in [-0.15, 0.05], k2 in ±0.05, p1 and p2 in ±1.5e-3, k3 in
// ±0.01. The workspace is the cube of the given half size about the origin;
// the base point is the centre of its bottom face. Throws std::invalid_argument
// on options that fail Validate().
Rig MakeSyntheticRig(const SyntheticRigOptions& options);

// A random scene for the rig, the same for the same seed: from the base
// point, first along +z, a circular arc bending by up to `max_bend_rad`, or
// (one time in two) an S-curve of two arcs bending each by 30-100% of it in
// opposite senses (second plane twisted by up to ±0.6 rad); bending plane at
// any azimuth; length 120-200 mm, radius 2.5-4 mm, lead-in 40 mm, and
// `num_tapes` red bands 3-6 mm wide spread over the middle 76% of the body.
// Guaranteed: the body and its radius stay 5 mm inside the workspace's side
// and top faces and above its bottom face, which the tube crosses at the base
// (the lead-in lies below it); the body projects at least 8 px inside every
// image; parts of the tube more than 8 radii apart along it keep a gap of 3
// radii. Draws again until a scene holds all that; throws
// std::invalid_argument when 500 draws do not (a rig too small for the tubes).
TubeScene RandomScene(const Rig& rig, uint32_t seed, double max_bend_rad, int num_tapes = 3);

}  // namespace shapesense
