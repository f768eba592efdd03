#pragma once

// From a tip position to a configuration: the inverse of the model's
// q -> tip map (configuration_geometry.h) over what the tendons can do.
// Three unknowns, kappa_x, kappa_z and eps1 (eps0 follows eps1), for the three
// coordinates of the tip; eps1 can be no lower than the compression that the
// tendons' minimum tension causes at that curvature. Levenberg-Marquardt with
// numerical derivatives: the map is smooth (sin t / t forms) and small.

#include "libs/geometry/types.h"
#include "libs/mechanics/tendon_model.h"

namespace shapesense {

struct TipSolution {
  Configuration configuration = Configuration::Zero();
  double residual = 0.0;  // distance of its tip from the asked one, mm
};

// The least eps1 the model reaches at these curvatures with every tendon at
// min_tension or more.
double MinimumDistalStrain(const TendonModel& model, double kappa_x, double kappa_z,
                           double min_tension);

// The reachable configuration whose tip is nearest `tip` (base frame, mm).
// The residual says whether it is reachable; the curvature is not bounded
// here (the caller checks it).
TipSolution ConfigurationForTip(const TendonModel& model, const Vec3& tip, double min_tension);

}  // namespace shapesense
