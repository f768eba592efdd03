#pragma once

// Simulated pose sets with known stiffnesses, for tests and for trying the
// estimators on a layout before building it (COLMAP-style synthetic data).

#include <random>
#include <vector>

#include "libs/mechanics/stiffness_estimation.h"
#include "libs/mechanics/tendon_model.h"

namespace shapesense {

struct SyntheticPoseOptions {
  int num_poses = 26;
  // Pose k bends the distal section by max_bend_angle * ((k mod 4) + 1) / 4
  // (rad over its rest length) toward bend_directions[k mod size] (rad, as
  // phi of ArcFit), or toward k times the golden angle when that is empty.
  double max_bend_angle = 1.2;
  std::vector<double> bend_directions;
  // Every tendon is held above a floor that steps through this range (N) from
  // pose to pose, so that pretension varies independently of the bend.
  double min_tension_low = 0.2;
  double min_tension_high = 2.0;
  // Standard deviations of the Gaussian noise on the sensed configuration
  // and the measured tensions (1/mm, -, N).
  double curvature_noise = 0.0;
  double strain_noise = 0.0;
  double tension_noise = 0.0;
};

// Displacements from the model's inverse (every tendon taut), the true
// configuration and tensions from its forward model, then the noise.
std::vector<PoseSample> SimulatePoses(const TendonModel& truth, const SyntheticPoseOptions& options,
                                      std::mt19937_64& rng);

}  // namespace shapesense
