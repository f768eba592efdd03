#pragma once

// Scoring the closed-loop experiment (the README's main demo): the plant is
// driven through a list of held target configurations once per controller
// mode, and each target is scored by how far the plant's TRUE tip sits from
// the target's tip over the last part of its hold (the steady state), in the
// manipulator's base frame. Pure computation, no I/O: the runner (`shapesense
// demo`, clients/tools/demo/closed_loop_experiment.h) collects the truth
// stream and writes the table, the JSON (its RunScoreToJson) and the picture
// (closed_loop_plot.h).

#include <cstdint>
#include <string>
#include <vector>

#include "libs/geometry/types.h"
#include "libs/mechanics/configuration.h"

namespace shapesense {

// One target of the experiment, as the controller resolves it.
struct ExperimentTarget {
  double start_s = 0.0;                     // when the target takes effect, s from the run's start
  double end_s = 0.0;                       // when the next one does
  Configuration q = Configuration::Zero();  // resolved target
};

// The plant's true configuration at a time (from the rig's truth messages).
struct ConfigurationSample {
  double time_s = 0.0;  // s from the run's start (same clock as the targets)
  Configuration q = Configuration::Zero();
};

struct TargetScore {
  int index = 0;
  Configuration target_q = Configuration::Zero();  // the target scored against
  Vec3 target_tip = Vec3::Zero();                  // base frame, mm
  Vec3 mean_tip = Vec3::Zero();                    // mean true tip over the steady-state window
  double tip_error_mm = 0.0;  // mean over the window of |tip(q_true) - tip(q_target)|
  double max_tip_error_mm = 0.0;
  // The same with each tip taken from its own distal section's start: what
  // is left once the proximal compression (eps0) is taken out.
  double distal_tip_error_mm = 0.0;
  int samples = 0;  // truth samples in the window (0: not scored)
};

struct RunScore {
  std::string mode;                     // "open_loop", "closed_loop", ...
  std::vector<TargetScore> targets;     // one per ExperimentTarget
  double mean_tip_error_mm = 0.0;       // mean over scored targets
  double max_tip_error_mm = 0.0;        // worst target mean
  double mean_tip_error_percent = 0.0;  // mean_tip_error_mm / L1 * 100
  int targets_scored = 0;

  // How many scored targets have tip_error_mm <= mm.
  int targets_within(double mm) const;
};

// Scores one run: each target's steady-state window is the last `window_s`
// of [start_s, end_s) (the whole hold when it is shorter). Targets with no
// sample in their window are left unscored (samples = 0) and excluded from
// the means. `truth` need not be in time order.
RunScore ScoreRun(const std::string& mode, const std::vector<ExperimentTarget>& targets,
                  const std::vector<ConfigurationSample>& truth, const SectionLengths& rest,
                  double window_s);

// The true tip path of a run, base frame, in time order (for the plot).
std::vector<Vec3> TipPath(const std::vector<ConfigurationSample>& truth,
                          const SectionLengths& rest);

// A plain-text table, one row per target: index (1-based), target curvatures
// (1/m), target tip (mm), then each run's steady-state tip error (mm, "-"
// when unscored) headed by its mode; then per run a summary line: mean and
// worst error in mm, the mean in % of L1, how many targets are within 1 mm.
std::string FormatExperimentTable(const std::vector<ExperimentTarget>& targets,
                                  const std::vector<RunScore>& runs, const SectionLengths& rest);

// The experiment's targets, shared by the demo and its end-to-end test.
struct ExperimentTargetOptions {
  int count = 20;
  double hold_s = 5.0;          // each target's hold, s
  double first_start_s = 1.0;   // when the first target takes effect, s
  uint32_t seed = 5;            // turns and jitters the spread of targets
  double max_bend_angle = 1.2;  // largest bend of the distal section, |kappa| * L1, rad
  double eps1 = 0.003;          // every target's distal strain (eps0 is 0)

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("count", count, "number of targets (1-1000)");
    visit("hold_s", hold_s, "how long each target is held, s (> 0)");
    visit("first_start_s", first_start_s, "when the first target takes effect, s (>= 0)");
    visit("seed", seed, "seed of the targets' spread");
    visit("max_bend_angle", max_bend_angle,
          "largest bend of the distal section, |kappa| * L1, rad (0-3.14]");
    visit("eps1", eps1, "axial strain of the distal section of every target [0-0.5)");
  }
  std::string Validate() const;
};

// `count` configurations spread evenly over the disc of bend vectors
// (theta cos phi, theta sin phi), theta = |kappa| * L1 <= max_bend_angle,
// kappa_x = theta / L1 cos phi, kappa_z = theta / L1 sin phi, eps0 = 0; ordered
// as a short tour of their tips from the one nearest the straight pose, so
// moves between targets are short. Target i holds from first_start_s +
// i * hold_s to first_start_s + (i + 1) * hold_s. Throws
// std::invalid_argument when the options fail Validate().
std::vector<ExperimentTarget> MakeExperimentTargets(const ExperimentTargetOptions& options,
                                                    const SectionLengths& rest);

}  // namespace shapesense
