#pragma once

// Rigid registration between paired point sets: the closed-form least-squares
// rotation and translation (Kabsch, by SVD) as the start, then Ceres with the
// rotation as a unit quaternion on its manifold, so that it stays orthonormal
// by construction, and an optional robust loss against stray pairs. Reports
// the RMS error per axis, as in the reference's validation.
//
// The reference's frame registration sits on top: articulate the manipulator
// toward each tendon in turn, sense the arcs in the cameras' frame, and
// register them to the model's arcs in the base frame (RegisterCurves).

#include <string>
#include <vector>

#include "libs/geometry/types.h"

namespace shapesense {

struct RegistrationOptions {
  // Huber loss scale, mm: pairs farther apart count linearly. 0: plain least
  // squares (then the closed form is already the optimum).
  double loss_scale = 0.0;
  int max_iterations = 50;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("loss_scale", loss_scale, "Huber loss scale, mm (0: plain least squares)");
    visit("max_iterations", max_iterations, "solver iterations (> 0)");
  }
  std::string Validate() const;
};

struct Registration {
  bool converged = false;
  std::string message;  // the solver's, or why the input was refused
  Pose3 target_from_source = Pose3::Identity();
  // RMS over the pairs of (target_from_source * source - target) along each
  // axis of the target frame, and in 3-D, mm.
  Vec3 rms_per_axis = Vec3::Zero();
  double rms = 0.0;
};

// Least-squares rotation and translation taking `source` onto `target`
// (same size, paired by index). Requires 3 or more points not on one line.
Pose3 AlignClosedForm(const Polyline& source, const Polyline& target);

// Refuses (converged = false, message) sets of different sizes, fewer than 3
// pairs or points on one line (the rotation about it is undetermined).
Registration RegisterPointSets(const Polyline& source, const Polyline& target,
                               const RegistrationOptions& options);

// Pairs every source curve with the target curve of the same index, each
// sampled at `samples_per_curve` equal fractions of its length from start to
// end, and registers all the pairs at once: e.g. the model's arcs (base
// frame) onto the sensed ones (world frame) gives world_from_base.
Registration RegisterCurves(const std::vector<Polyline>& source_curves,
                            const std::vector<Polyline>& target_curves, int samples_per_curve,
                            const RegistrationOptions& options);

}  // namespace shapesense
