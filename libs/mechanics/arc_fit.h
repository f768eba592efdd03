#pragma once

// Circular-arc fit of a sensed distal centreline (Ceres): the curvature
// vector (kappa_x, kappa_z), that is curvature and bending plane, that best
// explains the sensed points, the section's length taken as measured.
//
// Orthogonal-distance fit: every sensed point has its own arc length as a
// nuisance parameter, so noise along the centreline (which inflates the
// length of a noisy polyline, and so every arc length measured along it)
// does not bias the curvature. The first and last points are the ends of the
// section (s = 0 and s = length). A Huber loss keeps stray points from
// pulling the fit.
//
// Base-pose mode: the points are in another frame (the cameras' world) and
// the pose of the base in it is estimated jointly, from an initial guess:
// its position and the direction of its axis. The roll about the axis cannot
// be told from a centreline (it is the same as turning the bending plane),
// so it stays that of the initial guess.

#include <Eigen/Core>
#include <string>

#include "libs/geometry/types.h"
#include "libs/mechanics/configuration.h"

namespace shapesense {

struct ArcFitOptions {
  // Huber loss scale, mm: residuals beyond it count linearly. 0: plain
  // least squares.
  double loss_scale = 1.0;
  int max_iterations = 100;
  // Estimate world_from_base (position and axis direction) with the arc.
  bool estimate_base_pose = false;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("loss_scale", loss_scale, "Huber loss scale, mm (0: plain least squares)");
    visit("max_iterations", max_iterations, "solver iterations (> 0)");
    visit("estimate_base_pose", estimate_base_pose,
          "estimate the base pose (position and axis) with the arc");
  }
  std::string Validate() const;
};

struct ArcFitInput {
  // The sensed distal section, from its start to the tip, at least 3 points:
  // in the base frame, or in the frame of world_from_base.
  Polyline points;
  // Measured (compressed) lengths of the sections, mm, e.g. between the tape
  // markers. distal_length <= 0 takes the polyline's own length.
  double distal_length = 0.0;
  double proximal_length = 0.0;
  // Their standard deviations, mm (for the strains' variance; 0: exact).
  double distal_length_std = 0.0;
  double proximal_length_std = 0.0;
  // Rest lengths L0, L1 of the model, for the strains.
  SectionLengths rest;
  // The points' frame from the base frame: fixed, or the initial guess when
  // the base pose is estimated.
  Pose3 world_from_base = Pose3::Identity();
};

struct ArcFit {
  bool converged = false;
  std::string message;  // the solver's, or why the input was refused
  // kappa_x, kappa_z from the fit; eps0, eps1 from the measured lengths.
  Configuration configuration = Configuration::Zero();
  double curvature = 0.0;  // |kappa|, 1/mm
  // Bending plane: direction phi = atan2(z, x) in the base x-z plane toward
  // which the tip moves (kappa_x = |kappa| sin phi, kappa_z = -|kappa| cos phi).
  double bend_direction = 0.0;
  // Covariance of the configuration: the curvature block from the fit (scaled
  // by the residual variance), the strain block from the lengths' std.
  Eigen::Matrix4d covariance = Eigen::Matrix4d::Zero();
  double rms_residual = 0.0;  // distance of the points from the fitted arc, mm
  Pose3 world_from_base = Pose3::Identity();
};

ArcFit FitCircularArc(const ArcFitInput& input, const ArcFitOptions& options);

}  // namespace shapesense
