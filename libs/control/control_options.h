#pragma once

// Options of the tendon controller (config/controller.yaml; docs/control.md):
// the mode, the safety limits every command is held to, the sensing watchdog,
// the bounds on targets and the gains of each mode. Defaults suit the 4-tendon
// catheter of config/manipulator.yaml.

#include <string>
#include <vector>

namespace shapesense {

enum class ControlMode { kOpenLoop, kClosedLoop, kModelLess };

// "open_loop", "closed_loop", "model_less".
const char* ControlModeName(ControlMode mode);
// false when `name` is none of the above.
bool ParseControlMode(const std::string& name, ControlMode* mode);

// The displacement range of one tendon, mm.
struct TendonRange {
  double min = -1.0;
  double max = 6.5;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("min", min, "lowest displacement, mm");
    visit("max", max, "highest displacement, mm (> min)");
  }
  std::string Validate() const;
};

// What no command may exceed (enforced by the safety gate, safety_gate.h).
struct SafetyLimits {
  // Range of every tendon, unless tendon_ranges lists them one by one.
  TendonRange range;
  // Empty, or one range per tendon of the model, in the model's order.
  std::vector<TendonRange> tendon_ranges;
  // Fastest a tendon may move, mm/s.
  double max_rate = 2.0;
  // A late control step moves no farther than max_rate times this: the
  // actuator carries a command out over the coming period, not the one that
  // has passed.
  double max_step_period = 0.05;
  // Lowest tension any tendon may have per the model, N: keeps every tendon
  // taut (no slack, no lost motion when it is pulled again).
  double min_tension = 0.3;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("range", range, "displacement range of every tendon, mm (unless tendon_ranges is set)");
    visit("tendon_ranges", tendon_ranges,
          "per-tendon ranges [{min, max}, ...], one per tendon of the model (empty: use range)");
    visit("max_rate", max_rate, "fastest a tendon may move, mm/s (> 0)");
    visit("max_step_period", max_step_period,
          "longest period one command's step may use at max_rate, s (> 0)");
    visit("min_tension", min_tension, "lowest tension of any tendon per the model, N (>= 0)");
  }
  std::string Validate() const;
  // Also checks tendon_ranges against the model's number of tendons.
  std::string ValidateFor(int num_tendons) const;
  TendonRange RangeOf(int tendon) const;
};

// Age of the last valid sensed configuration at which the controller holds
// (stale) and at which it stops (lost).
struct WatchdogOptions {
  bool enabled = true;
  double hold_age = 0.2;  // s
  double lost_age = 1.0;  // s

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("enabled", enabled,
          "hold and stop on stale or lost sensing (off: open loop without cameras)");
    visit("hold_age", hold_age, "sensing older than this holds the command, s (> 0)");
    visit("lost_age", lost_age, "sensing older than this stops until re-armed, s (> hold_age)");
  }
  std::string Validate() const;
};

// Bounds on targets: what a trajectory or a streamed target may ask for.
struct WorkspaceOptions {
  // Largest bend of the distal section over its rest length, rad: the
  // curvature bound is max_bend_angle / distal_length.
  double max_bend_angle = 2.0;
  // Largest compressive strain eps1 of the distal section.
  double max_distal_strain = 0.05;
  // A tip-position target is reachable when a configuration puts the tip
  // this close to it, mm.
  double tip_tolerance = 0.05;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("max_bend_angle", max_bend_angle,
          "largest bend of the distal section over its rest length, rad (0-6.28]");
    visit("max_distal_strain", max_distal_strain,
          "largest compressive strain eps1 of the distal section (0-0.5]");
    visit("tip_tolerance", tip_tolerance,
          "a tip target is reachable within this distance, mm (> 0)");
  }
  std::string Validate() const;
};

// Closed loop: y = model inverse of (target + correction), the correction a
// PI of the sensed error in (kappa_x, kappa_z, eps1), with anti-windup.
struct ClosedLoopOptions {
  double proportional = 0.3;  // correction per unit error
  double integral = 2.0;      // 1/s
  // Conditional integration: the integral does not grow toward what the
  // model's inverse and the safety gate did not carry out at the last step.
  bool anti_windup = true;
  // Largest correction, as a bend angle over the distal length, rad, and as
  // a strain.
  double max_correction_bend = 0.5;
  double max_correction_strain = 0.01;
  // Each part of the integral, the curvatures' and eps1's, holds while its
  // error, as tip motion (|kappa error| L1^2 / 2, |eps1 error| L1), is
  // within this, mm. Play on the tendons (backlash) otherwise makes the
  // integral hunt: it creeps through the play band while the tip stands
  // still, then the tip jumps past the target, again and again; and a small
  // bias in the sensed eps1 lets the pretension drift until the play lets
  // go. 0: always integrate.
  double integral_deadband_mm = 0.3;
  // The proportional gain on the eps1 error, as a fraction of that on the
  // curvatures. eps1 is sensed from the distal band's arc length, several
  // times noisier than the bend, and every change of it moves all tendons at
  // once (pretension), which unequal play turns into bending: at full gain
  // the sensing noise on eps1 alone shook the tip by 1-2 mm.
  double strain_proportional = 0.1;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("proportional", proportional, "proportional gain on the sensed error (>= 0)");
    visit("integral", integral, "integral gain, 1/s (>= 0)");
    visit("anti_windup", anti_windup,
          "do not integrate toward what the inverse and the gate did not carry out");
    visit("integral_deadband_mm", integral_deadband_mm,
          "each part of the integral (curvatures, eps1) holds while its error, as tip motion, is "
          "within this, mm (>= 0; stops hunting through tendon play; 0: always integrate)");
    visit("strain_proportional", strain_proportional,
          "proportional gain on the eps1 error, as a fraction of that on the curvatures [0-1] "
          "(eps1 is sensed noisier, and moves every tendon at once)");
    visit("max_correction_bend", max_correction_bend,
          "largest curvature correction, as a bend over the distal length, rad (> 0)");
    visit("max_correction_strain", max_correction_strain, "largest strain correction (> 0)");
  }
  std::string Validate() const;
};

// Model-less: the Jacobian of the curvatures (kappa_x, kappa_z) to the
// displacements, started from the model's A, updated by Broyden from sensed
// motion; steps by damped least squares. Curvature errors are weighed as tip
// motion, L1^2 / 2 mm per 1/mm. How the tendons share the step and the
// pretension (eps1) come from the model's minimum-tension inverse, eps1
// moved toward the sensed error at the same gain (controllers.h).
struct ModelLessOptions {
  double gain = 4.0;  // 1/s: fraction of the error removed per second
  // Damping of the least-squares step, tip mm per tendon mm.
  double damping = 5.0;
  // Fraction of the Broyden correction applied per update (0-1].
  double broyden_weight = 0.2;
  // Smallest tendon motion between two samples that updates the Jacobian, mm.
  double min_update_step = 0.01;
  // Each update pulls the estimate this fraction back toward the model's A,
  // so friction (motion that shows no response) cannot wear it to zero.
  double model_prior_weight = 0.02;
  // The least-tensioned tendon is held this far above min_tension, N.
  double pretension_margin = 0.02;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("gain", gain, "fraction of the sensed error removed per second, 1/s (> 0)");
    visit("damping", damping, "damping of the least-squares step, tip mm per tendon mm (> 0)");
    visit("broyden_weight", broyden_weight, "fraction of each Broyden update applied (0-1]");
    visit("min_update_step", min_update_step,
          "smallest tendon motion between samples that updates the Jacobian, mm (> 0)");
    visit("model_prior_weight", model_prior_weight,
          "pull of each update back toward the model's Jacobian [0-1)");
    visit("pretension_margin", pretension_margin,
          "the least tension is held this far above limits.min_tension, N (>= 0)");
  }
  std::string Validate() const;
};

struct ControllerOptions {
  std::string mode = "closed_loop";
  // Rate of the control loop, Hz (the controller service's).
  double loop_rate = 100.0;
  SafetyLimits limits;
  WatchdogOptions watchdog;
  WorkspaceOptions workspace;
  ClosedLoopOptions closed_loop;
  ModelLessOptions model_less;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("mode", mode, "open_loop | closed_loop | model_less");
    visit("loop_rate", loop_rate, "control loop rate, Hz (1-10000)");
    visit("limits", limits, "limits every command is held to (the safety gate)");
    visit("watchdog", watchdog, "what stale or lost sensing does");
    visit("workspace", workspace, "bounds on targets");
    visit("closed_loop", closed_loop, "gains of closed_loop");
    visit("model_less", model_less, "gains of model_less");
  }
  std::string Validate() const;
  ControlMode control_mode() const;  // of a validated `mode`
};

// Throws InputError("source: key: what") on bad YAML, unknown keys, wrong
// types or values that fail Validate().
ControllerOptions ParseControllerYaml(const std::string& text, const std::string& source);

// The documented defaults, as config/controller.yaml holds them.
std::string ControllerDocumentedYaml();

}  // namespace shapesense
