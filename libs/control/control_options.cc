#include "libs/control/control_options.h"

#include <cmath>
#include <initializer_list>
#include <limits>
#include <numbers>
#include <sstream>

#include "libs/config/options_yaml.h"
#include "libs/core/error.h"

namespace shapesense {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

std::string ExpectPositive(const std::string& key, double value) {
  return ExpectWithin(key, value, {0.0, kInfinity, true, true}, "a positive number");
}

std::string ExpectNonNegative(const std::string& key, double value) {
  return ExpectWithin(key, value, {0.0, kInfinity, false, true}, "a number >= 0");
}

std::string FirstError(std::initializer_list<std::string> errors) {
  for (const std::string& error : errors) {
    if (!error.empty()) return error;
  }
  return "";
}

std::string Prefixed(const std::string& prefix, const std::string& error) {
  return error.empty() ? "" : prefix + error;
}

}  // namespace

const char* ControlModeName(ControlMode mode) {
  switch (mode) {
    case ControlMode::kOpenLoop:
      return "open_loop";
    case ControlMode::kClosedLoop:
      return "closed_loop";
    case ControlMode::kModelLess:
      return "model_less";
  }
  return "?";
}

bool ParseControlMode(const std::string& name, ControlMode* mode) {
  for (ControlMode m :
       {ControlMode::kOpenLoop, ControlMode::kClosedLoop, ControlMode::kModelLess}) {
    if (name == ControlModeName(m)) {
      *mode = m;
      return true;
    }
  }
  return false;
}

std::string TendonRange::Validate() const {
  if (!std::isfinite(min) || !std::isfinite(max) || !(min < max)) {
    return "min, max: expected finite numbers with min < max, got " + Number(min) + ", " +
           Number(max);
  }
  return "";
}

std::string SafetyLimits::Validate() const {
  if (std::string error = range.Validate(); !error.empty()) return "range." + error;
  for (size_t i = 0; i < tendon_ranges.size(); ++i) {
    if (std::string error = tendon_ranges[i].Validate(); !error.empty()) {
      return "tendon_ranges[" + std::to_string(i) + "]." + error;
    }
  }
  return FirstError({ExpectPositive("max_rate", max_rate),
                     ExpectPositive("max_step_period", max_step_period),
                     ExpectNonNegative("min_tension", min_tension)});
}

std::string SafetyLimits::ValidateFor(int num_tendons) const {
  if (std::string error = Validate(); !error.empty()) return error;
  if (!tendon_ranges.empty() && static_cast<int>(tendon_ranges.size()) != num_tendons) {
    return "tendon_ranges: expected one range per tendon of the model (" +
           std::to_string(num_tendons) + "), got " + std::to_string(tendon_ranges.size());
  }
  return "";
}

TendonRange SafetyLimits::RangeOf(int tendon) const {
  if (tendon_ranges.empty()) return range;
  return tendon_ranges.at(static_cast<size_t>(tendon));
}

std::string WatchdogOptions::Validate() const {
  if (std::string error = ExpectPositive("hold_age", hold_age); !error.empty()) return error;
  return ExpectWithin("lost_age", lost_age, {hold_age, kInfinity, true, true},
                      "a number of seconds above hold_age (" + Number(hold_age) + ")");
}

std::string WorkspaceOptions::Validate() const {
  return FirstError(
      {ExpectWithin("max_bend_angle", max_bend_angle, {0.0, 2.0 * std::numbers::pi, true, false},
                    "an angle in (0, 2 pi], rad"),
       ExpectWithin("max_distal_strain", max_distal_strain, {0.0, 0.5, true, false},
                    "a strain in (0, 0.5]"),
       ExpectPositive("tip_tolerance", tip_tolerance)});
}

std::string ClosedLoopOptions::Validate() const {
  return FirstError({ExpectNonNegative("proportional", proportional),
                     ExpectNonNegative("integral", integral),
                     ExpectPositive("max_correction_bend", max_correction_bend),
                     ExpectPositive("max_correction_strain", max_correction_strain),
                     ExpectNonNegative("integral_deadband_mm", integral_deadband_mm),
                     ExpectWithin("strain_proportional", strain_proportional,
                                  {0.0, 1.0, false, false}, "a fraction in [0, 1]")});
}

std::string ModelLessOptions::Validate() const {
  return FirstError({ExpectPositive("gain", gain), ExpectPositive("damping", damping),
                     ExpectWithin("broyden_weight", broyden_weight, {0.0, 1.0, true, false},
                                  "a fraction in (0, 1]"),
                     ExpectPositive("min_update_step", min_update_step),
                     ExpectWithin("model_prior_weight", model_prior_weight, {0.0, 1.0, false, true},
                                  "a fraction in [0, 1)"),
                     ExpectNonNegative("pretension_margin", pretension_margin)});
}

std::string ControllerOptions::Validate() const {
  ControlMode parsed;
  if (!ParseControlMode(mode, &parsed)) {
    return "mode: expected open_loop, closed_loop or model_less, got " + mode;
  }
  return FirstError({ExpectWithin("loop_rate", loop_rate, {1.0, 10000.0, false, false},
                                  "a rate in [1, 10000], Hz"),
                     Prefixed("limits.", limits.Validate()),
                     Prefixed("watchdog.", watchdog.Validate()),
                     Prefixed("workspace.", workspace.Validate()),
                     Prefixed("closed_loop.", closed_loop.Validate()),
                     Prefixed("model_less.", model_less.Validate())});
}

ControlMode ControllerOptions::control_mode() const {
  ControlMode parsed = ControlMode::kClosedLoop;
  ParseControlMode(mode, &parsed);
  return parsed;
}

ControllerOptions ParseControllerYaml(const std::string& text, const std::string& source) {
  return OptionsFromYamlText<ControllerOptions>(text, source);
}

std::string ControllerDocumentedYaml() {
  return "# Options of the tendon controller (docs/control.md). Every key is optional; these are\n"
         "# the defaults, which suit the catheter of config/manipulator.yaml. Displacements in\n"
         "# mm (positive = pulled), tensions in N, times in s.\n" +
         OptionsToDocumentedYaml(ControllerOptions{});
}

}  // namespace shapesense
