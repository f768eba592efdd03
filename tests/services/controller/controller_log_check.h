#pragma once

// Reading the controller's CSV log back, and checking every logged command
// against the limits again, from the log alone.

#include <filesystem>
#include <string>
#include <vector>

#include "libs/control/control_options.h"
#include "libs/mechanics/tendon_model.h"

namespace shapesense::testing {

struct ControllerCsv {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;
  int bad_rows = 0;  // rows without one field per column

  int Column(const std::string& name) const;  // -1 when absent
  double Number(size_t row, const std::string& name) const;
  const std::string& Text(size_t row, const std::string& name) const;
};

ControllerCsv ReadControllerCsv(const std::filesystem::path& path);

struct LimitCheck {
  int commands = 0;
  int range = 0;
  int rate = 0;
  int tension = 0;
  int logged_tension_mismatch = 0;  // the tension columns against the model
  // Commands with a tension below the minimum that the gate let through
  // while healing from an unsafe start (none lower than the row before).
  int below_floor = 0;
  std::string first;  // the first violation, in words
  int total() const { return range + rate + tension + logged_tension_mismatch; }
};

// Every row's command: within each tendon's range, every tension (per the
// model) at least the minimum, and no tendon moved from the previous row's
// command faster than max_rate * min(dt, max_step_period), dt from the rows'
// times. From an unsafe start (slack tendons at power-up) the gate heals: a
// tension below the minimum is allowed (and counted in below_floor) when it
// is no lower than in the row before (the first row: the measured
// positions), as docs/control.md says.
LimitCheck CheckLoggedCommands(const ControllerCsv& csv, const TendonModel& model,
                               const SafetyLimits& limits);

}  // namespace shapesense::testing
