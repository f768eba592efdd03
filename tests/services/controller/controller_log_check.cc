#include "tests/services/controller/controller_log_check.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "libs/control/safety_gate.h"
#include "libs/core/csv_fields.h"

namespace shapesense::testing {
namespace {

Eigen::VectorXd Vector(const ControllerCsv& csv, size_t row, const std::string& prefix, int n) {
  Eigen::VectorXd values(n);
  for (int i = 0; i < n; ++i) values(i) = csv.Number(row, prefix + std::to_string(i));
  return values;
}

void Violation(LimitCheck* check, int* counter, const std::string& what) {
  ++*counter;
  if (check->first.empty()) check->first = what;
}

}  // namespace

int ControllerCsv::Column(const std::string& name) const {
  const auto it = std::find(columns.begin(), columns.end(), name);
  return it == columns.end() ? -1 : static_cast<int>(it - columns.begin());
}

double ControllerCsv::Number(size_t row, const std::string& name) const {
  return std::strtod(Text(row, name).c_str(), nullptr);
}

const std::string& ControllerCsv::Text(size_t row, const std::string& name) const {
  static const std::string kNone;
  const int column = Column(name);
  return column < 0 ? kNone : rows.at(row).at(static_cast<size_t>(column));
}

ControllerCsv ReadControllerCsv(const std::filesystem::path& path) {
  ControllerCsv csv;
  std::ifstream in(path);
  std::string line;
  if (std::getline(in, line)) csv.columns = SplitCsvFields(line);
  while (std::getline(in, line)) {
    std::vector<std::string> fields = SplitCsvFields(line);
    if (fields.size() != csv.columns.size()) {
      ++csv.bad_rows;
      continue;
    }
    csv.rows.push_back(std::move(fields));
  }
  return csv;
}

LimitCheck CheckLoggedCommands(const ControllerCsv& csv, const TendonModel& model,
                               const SafetyLimits& limits) {
  const SafetyEnvelope envelope(model, limits);
  const int n = model.num_tendons();
  LimitCheck check;
  Eigen::VectorXd previous;
  double previous_time = 0.0;
  // Where the gate started: the actuators' positions.
  Eigen::VectorXd floor = Eigen::VectorXd::Constant(n, limits.min_tension);
  if (!csv.rows.empty()) {
    floor = floor.cwiseMin(envelope.Tensions(Vector(csv, 0, "measured_", n)));
  }
  for (size_t row = 0; row < csv.rows.size(); ++row) {
    const Eigen::VectorXd command = Vector(csv, row, "command_", n);
    const double time = csv.Number(row, "time_s");
    const std::string where =
        "row " + std::to_string(row + 1) + " (t " + std::to_string(time) + ")";
    ++check.commands;
    if ((command - envelope.low()).minCoeff() < 0.0 ||
        (envelope.high() - command).minCoeff() < 0.0 || !command.allFinite()) {
      Violation(&check, &check.range, where + ": out of range");
    }
    const Eigen::VectorXd tensions = envelope.Tensions(command);
    if ((tensions - floor).minCoeff() < -1e-9) {
      Violation(&check, &check.tension, where + ": tension " + std::to_string(tensions.minCoeff()));
    }
    if (tensions.minCoeff() < limits.min_tension - 1e-9) ++check.below_floor;
    floor = tensions.cwiseMin(limits.min_tension);
    if ((tensions - Vector(csv, row, "tension_", n)).cwiseAbs().maxCoeff() > 1e-9) {
      Violation(&check, &check.logged_tension_mismatch, where + ": logged tension differs");
    }
    if (previous.size() == n) {
      const double dt = time - previous_time;
      const double max_step = limits.max_rate * std::min(dt, limits.max_step_period);
      const double step = (command - previous).cwiseAbs().maxCoeff();
      if (step > max_step * (1.0 + 1e-9) + 1e-12) {
        Violation(&check, &check.rate,
                  where + ": step " + std::to_string(step) + " mm > " + std::to_string(max_step));
      }
    }
    previous = command;
    previous_time = time;
  }
  return check;
}

}  // namespace shapesense::testing
