#pragma once

// The virtual rig's manipulator: commanded tendon displacements in, shape
// out, through a plant that differs from the controller's model the way a
// real one does (docs/control.md, "The plant"):
//
//   commanded y ──► play (friction deadband + hysteresis, per tendon)
//               ──► actual y ──► TendonModel with stiffnesses off nominal,
//                                slack tendons carrying no tension
//                                (SolveWithSlack) ──► q ──► centreline
//
// The play is a backlash operator: the tendon's far end follows the
// actuator only once the actuator has taken up the play, so a reversal moves
// nothing for `width` mm and the end sits width/2 behind the command in the
// direction of the last motion. Its state persists between steps. Quasi-
// static: each command settles at once. Randomness (the spread of the
// stiffness errors and of the play) comes from the seed only.

#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <string>

#include "libs/geometry/types.h"
#include "libs/mechanics/tendon_model.h"

namespace shapesense {

// Multipliers of the nominal model's stiffnesses.
struct PlantStiffnessFactors {
  double bend_x = 1.0;
  double bend_z = 1.0;
  double axial_proximal = 1.0;
  double axial_distal = 1.0;
  double tendon = 1.0;  // every tendon's K_t

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("bend_x", bend_x, "factor on K_x (0.5-2)");
    visit("bend_z", bend_z, "factor on K_z (0.5-2)");
    visit("axial_proximal", axial_proximal, "factor on K_a0 (0.5-2)");
    visit("axial_distal", axial_distal, "factor on K_a1 (0.5-2)");
    visit("tendon", tendon, "factor on every tendon's K_t (0.5-2)");
  }
  std::string Validate() const;
};

struct TendonPlantOptions {
  PlantStiffnessFactors stiffness_factor;
  // Each factor is further multiplied by 1 + u, u drawn uniformly in
  // [-random_stiffness_error, random_stiffness_error] from the seed.
  double random_stiffness_error = 0.0;
  // Width of each tendon's play band, mm (0: none).
  double tendon_play = 0.0;
  // Each tendon's play is tendon_play * (1 + u), u uniform in +-this, from the seed.
  double tendon_play_spread = 0.0;
  // Spacing of the centreline's points, mm.
  double centerline_spacing = 0.5;
  uint32_t seed = 0;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("stiffness_factor", stiffness_factor, "the plant's stiffnesses over the model's");
    visit("random_stiffness_error", random_stiffness_error,
          "each factor also times 1 + U(-e, e) from the seed [0-0.5]");
    visit("tendon_play", tendon_play, "width of each tendon's play (backlash) band, mm (>= 0)");
    visit("tendon_play_spread", tendon_play_spread,
          "each tendon's play times 1 + U(-s, s) from the seed [0-1]");
    visit("centerline_spacing", centerline_spacing, "spacing of the centreline points, mm (> 0)");
    visit("seed", seed, "seed of the random stiffness errors and play spread");
  }
  std::string Validate() const;
};

// The backlash operator: `output` moves only when `input` leaves the band
// [output - width/2, output + width/2], and then to its edge.
double PlayOperator(double output, double input, double width);

class TendonPlant {
 public:
  // `nominal`: the controller's model file; the plant's own model is drawn
  // from it and the options. The actuators start at `initial` with each
  // tendon's end centred in its play. Throws std::invalid_argument on
  // options that fail Validate() or a wrong size of `initial`.
  TendonPlant(const ManipulatorOptions& nominal, const TendonPlantOptions& options,
              const Eigen::VectorXd& initial);

  // Moves the actuators to `commanded` and lets the manipulator settle.
  // Throws std::invalid_argument on a wrong size or non-finite entries.
  void Command(const Eigen::VectorXd& commanded);

  const Eigen::VectorXd& commanded() const { return commanded_; }
  // Displacements that reach the tendons' far ends, after the play, mm.
  const Eigen::VectorXd& tendon_displacements() const { return actual_; }
  const TendonState& state() const { return state_; }
  const Configuration& configuration() const { return state_.configuration; }
  Pose3 BaseFromTip() const;
  // Base to tip, base frame, points at most centerline_spacing apart.
  Polyline Centerline() const;

  const TendonModel& true_model() const { return model_; }
  const Eigen::VectorXd& play_widths() const { return play_; }

 private:
  // The draws: the stiffness errors first, then the play spread.
  TendonPlant(const ManipulatorOptions& nominal, const TendonPlantOptions& options,
              const Eigen::VectorXd& initial, std::mt19937_64 rng);

  TendonModel model_;
  TendonPlantOptions options_;
  Eigen::VectorXd play_;
  Eigen::VectorXd commanded_;
  Eigen::VectorXd actual_;
  TendonState state_;
};

}  // namespace shapesense
