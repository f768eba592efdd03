#include "libs/mechanics/synthetic_poses.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace shapesense {
namespace {

double BendDirection(const SyntheticPoseOptions& options, int k) {
  if (options.bend_directions.empty()) {
    const double golden_angle = std::numbers::pi * (3.0 - std::sqrt(5.0));
    return golden_angle * k;
  }
  return options.bend_directions[static_cast<size_t>(k) % options.bend_directions.size()];
}

// Steps through [low, high] in an order unrelated to the bend's magnitude.
double TensionFloor(const SyntheticPoseOptions& options, int k) {
  const int count = std::max(options.num_poses, 2);
  const double fraction = static_cast<double>((7 * k) % count) / (count - 1);
  return options.min_tension_low + fraction * (options.min_tension_high - options.min_tension_low);
}

Eigen::VectorXd Noise(int size, double std_dev, std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::VectorXd out(size);
  for (int i = 0; i < size; ++i) out(i) = std_dev * normal(rng);
  return out;
}

}  // namespace

std::vector<PoseSample> SimulatePoses(const TendonModel& truth, const SyntheticPoseOptions& options,
                                      std::mt19937_64& rng) {
  std::vector<PoseSample> poses;
  const double distal = truth.lengths().distal;
  for (int k = 0; k < options.num_poses; ++k) {
    const double bend = options.max_bend_angle * ((k % 4) + 1) / 4.0;
    Configuration desired = Configuration::Zero();
    desired.head<2>() = CurvatureTowards(BendDirection(options, k), bend, distal);
    PoseSample pose;
    pose.displacements =
        truth.InverseWithMinimumTension(desired, TensionFloor(options, k)).displacements;
    const TendonState state = truth.Solve(pose.displacements);
    const Eigen::Vector4d noise_levels(options.curvature_noise, options.curvature_noise,
                                       options.strain_noise, options.strain_noise);
    pose.configuration = state.configuration + noise_levels.cwiseProduct(Noise(4, 1.0, rng));
    pose.tensions = state.tensions + Noise(truth.num_tendons(), options.tension_noise, rng);
    poses.push_back(pose);
  }
  return poses;
}

}  // namespace shapesense
