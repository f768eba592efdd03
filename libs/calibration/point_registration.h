#pragma once

// Rigid registration of corresponding point sets, as in the reference's
// accuracy validation: points the system sensed (e.g. a stylus tip found in
// the voxels) against the same points measured by a reference digitizer.
// The solver is libs/registration's (closed form, then Ceres over a unit
// quaternion with an optional robust loss); this adds the per-point report
// the calibration tools print and plot.

#include <vector>

#include "libs/geometry/types.h"
#include "libs/registration/rigid_registration.h"

namespace shapesense {

struct PointRegistration {
  // Maps sensed points into the reference's frame.
  Pose3 reference_from_sensed = Pose3::Identity();
  // reference_from_sensed * sensed - reference, per point, mm (reference frame).
  std::vector<Vec3> errors;
  Vec3 rms_per_axis = Vec3::Zero();  // mm
  double rms = 0.0;                  // 3-D RMS error, mm
  double max_error = 0.0;            // largest 3-D error, mm
};

// Throws InputError when the sets differ in size, hold fewer than 3 points,
// or the points are (nearly) collinear, which leaves a rotation free;
// std::invalid_argument on options that fail Validate().
PointRegistration RegisterPoints(const std::vector<Vec3>& sensed,
                                 const std::vector<Vec3>& reference,
                                 const RegistrationOptions& options = {});

}  // namespace shapesense
