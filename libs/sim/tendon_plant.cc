#include "libs/sim/tendon_plant.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

#include "libs/core/error.h"
#include "libs/mechanics/configuration_geometry.h"

namespace shapesense {
namespace {

// Uniform in [-spread, spread], drawn even when spread is 0 so that one seed
// gives the same draws whichever spreads are set.
double Jitter(std::mt19937_64& rng, double spread) {
  return spread * std::uniform_real_distribution<double>(-1.0, 1.0)(rng);
}

// The plant's own manipulator: the nominal one with its stiffnesses scaled.
ManipulatorOptions PlantManipulator(ManipulatorOptions nominal, const TendonPlantOptions& options,
                                    std::mt19937_64& rng) {
  const PlantStiffnessFactors& f = options.stiffness_factor;
  const double e = options.random_stiffness_error;
  StiffnessOptions& k = nominal.stiffness;
  k.bend_x *= f.bend_x * (1.0 + Jitter(rng, e));
  k.bend_z *= f.bend_z * (1.0 + Jitter(rng, e));
  k.axial_proximal *= f.axial_proximal * (1.0 + Jitter(rng, e));
  k.axial_distal *= f.axial_distal * (1.0 + Jitter(rng, e));
  const double tendon = f.tendon * (1.0 + Jitter(rng, e));
  for (TendonOptions& t : nominal.tendons) t.stiffness *= tendon;
  return nominal;
}

Eigen::VectorXd PlayWidths(int tendons, const TendonPlantOptions& options, std::mt19937_64& rng) {
  Eigen::VectorXd widths(tendons);
  for (int i = 0; i < tendons; ++i) {
    widths(i) = options.tendon_play * (1.0 + Jitter(rng, options.tendon_play_spread));
  }
  return widths;
}

TendonModel CheckedPlantModel(const ManipulatorOptions& nominal, const TendonPlantOptions& options,
                              std::mt19937_64& rng) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw std::invalid_argument("tendon plant: " + error);
  }
  return TendonModel(PlantManipulator(nominal, options, rng));
}

}  // namespace

std::string PlantStiffnessFactors::Validate() const {
  for (const std::string& error :
       {ExpectWithin("bend_x", bend_x, {0.5, 2.0}), ExpectWithin("bend_z", bend_z, {0.5, 2.0}),
        ExpectWithin("axial_proximal", axial_proximal, {0.5, 2.0}),
        ExpectWithin("axial_distal", axial_distal, {0.5, 2.0}),
        ExpectWithin("tendon", tendon, {0.5, 2.0})}) {
    if (!error.empty()) return error;
  }
  return "";
}

std::string TendonPlantOptions::Validate() const {
  if (std::string error = stiffness_factor.Validate(); !error.empty()) {
    return "stiffness_factor." + error;
  }
  for (const std::string& error :
       {ExpectWithin("random_stiffness_error", random_stiffness_error, {0.0, 0.5}),
        ExpectWithin("tendon_play", tendon_play, {0.0, 1e3}),
        ExpectWithin("tendon_play_spread", tendon_play_spread, {0.0, 1.0})}) {
    if (!error.empty()) return error;
  }
  if (!std::isfinite(centerline_spacing) || centerline_spacing <= 0.0) {
    return "centerline_spacing: expected a positive number, got " + Number(centerline_spacing);
  }
  return "";
}

double PlayOperator(double output, double input, double width) {
  const double half = width / 2.0;
  return std::clamp(output, input - half, input + half);
}

TendonPlant::TendonPlant(const ManipulatorOptions& nominal, const TendonPlantOptions& options,
                         const Eigen::VectorXd& initial)
    : TendonPlant(nominal, options, initial, std::mt19937_64(options.seed)) {}

TendonPlant::TendonPlant(const ManipulatorOptions& nominal, const TendonPlantOptions& options,
                         const Eigen::VectorXd& initial, std::mt19937_64 rng)
    : model_(CheckedPlantModel(nominal, options, rng)),
      options_(options),
      play_(PlayWidths(model_.num_tendons(), options, rng)) {
  if (initial.size() != model_.num_tendons() || !initial.allFinite()) {
    throw std::invalid_argument("tendon plant: expected " + std::to_string(model_.num_tendons()) +
                                " finite initial displacements");
  }
  commanded_ = initial;
  actual_ = initial;
  state_ = model_.SolveWithSlack(actual_);
}

void TendonPlant::Command(const Eigen::VectorXd& commanded) {
  if (commanded.size() != model_.num_tendons() || !commanded.allFinite()) {
    throw std::invalid_argument("tendon plant: expected " + std::to_string(model_.num_tendons()) +
                                " finite displacements");
  }
  commanded_ = commanded;
  for (int i = 0; i < actual_.size(); ++i) {
    actual_(i) = PlayOperator(actual_(i), commanded(i), play_(i));
  }
  state_ = model_.SolveWithSlack(actual_);
}

Pose3 TendonPlant::BaseFromTip() const {
  return shapesense::BaseFromTip(state_.configuration, model_.lengths());
}

Polyline TendonPlant::Centerline() const {
  return CenterlineFromConfiguration(state_.configuration, model_.lengths(),
                                     options_.centerline_spacing);
}

}  // namespace shapesense
