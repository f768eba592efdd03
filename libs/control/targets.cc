#include "libs/control/targets.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <set>
#include <sstream>
#include <stdexcept>

#include "libs/control/tip_solver.h"
#include "libs/core/csv_fields.h"
#include "libs/core/error.h"

namespace shapesense {
namespace {

[[noreturn]] void Fail(const std::string& source, const std::string& where,
                       const std::string& what) {
  throw InputError(DescribeInputError(source, where, what));
}

// ---- YAML ----

void RejectUnknownKeys(const YAML::Node& map, const std::set<std::string>& known,
                       const std::string& source, const std::string& where) {
  for (const auto& entry : map) {
    const std::string key = entry.first.as<std::string>();
    if (!known.contains(key)) Fail(source, where + key, "unknown key");
  }
}

double FiniteNumber(const YAML::Node& node, const std::string& source, const std::string& where) {
  double value = 0.0;
  try {
    if (!node.IsScalar()) throw YAML::Exception(YAML::Mark::null_mark(), "not a scalar");
    value = node.as<double>();
  } catch (const YAML::Exception&) {
    Fail(source, where, "expected a number");
  }
  if (!std::isfinite(value)) Fail(source, where, "expected a finite number, got " + Number(value));
  return value;
}

Eigen::VectorXd FiniteNumbers(const YAML::Node& node, int count, const std::string& source,
                              const std::string& where) {
  if (!node.IsSequence() || static_cast<int>(node.size()) != count) {
    Fail(source, where, "expected a sequence of " + std::to_string(count) + " numbers");
  }
  Eigen::VectorXd values(count);
  for (int i = 0; i < count; ++i) {
    values(i) =
        FiniteNumber(node[static_cast<size_t>(i)], source, where + "[" + std::to_string(i) + "]");
  }
  return values;
}

Target TargetFromYaml(const YAML::Node& node, const std::string& source, const std::string& where) {
  if (!node.IsMap()) Fail(source, where, "expected a map {time, q} or {time, tip}");
  RejectUnknownKeys(node, {"time", "q", "tip"}, source, where + ".");
  if (!node["time"]) Fail(source, where + ".time", "missing");
  if (static_cast<bool>(node["q"]) == static_cast<bool>(node["tip"])) {
    Fail(source, where,
         "expected exactly one of q (kappa_x, kappa_z, eps0, eps1) and tip (x, y, z)");
  }
  Target target;
  target.time = FiniteNumber(node["time"], source, where + ".time");
  if (node["q"]) {
    target.configuration = FiniteNumbers(node["q"], 4, source, where + ".q");
  } else {
    target.kind = TargetKind::kTipPosition;
    target.tip = FiniteNumbers(node["tip"], 3, source, where + ".tip");
  }
  return target;
}

bool InterpolationFromYaml(const YAML::Node& node, const std::string& source) {
  if (!node) return true;
  const std::string value = node.IsScalar() ? node.as<std::string>() : "";
  if (value != "linear" && value != "step") {
    Fail(source, "interpolation", "expected linear or step, got " + value);
  }
  return value == "linear";
}

// ---- CSV ----

const std::vector<std::string> kConfigurationColumns = {"time", "kappa_x", "kappa_z", "eps0",
                                                        "eps1"};
const std::vector<std::string> kTipColumns = {"time", "tip_x", "tip_y", "tip_z"};

// Index of each expected column in the header; throws when the header is neither set.
std::vector<int> ColumnOrder(const std::vector<std::string>& header,
                             const std::vector<std::string>& expected) {
  std::vector<int> order;
  for (const std::string& name : expected) {
    const auto found = std::find(header.begin(), header.end(), name);
    if (found == header.end()) return {};
    order.push_back(static_cast<int>(found - header.begin()));
  }
  return header.size() == expected.size() ? order : std::vector<int>{};
}

double CsvNumber(const std::string& field, const std::string& source, const std::string& where) {
  char* end = nullptr;
  const double value = std::strtod(field.c_str(), &end);
  if (field.empty() || end != field.c_str() + field.size()) {
    Fail(source, where, "expected a number, got '" + field + "'");
  }
  if (!std::isfinite(value)) Fail(source, where, "expected a finite number, got " + field);
  return value;
}

Target TargetFromCsvRow(const std::vector<std::string>& fields, const std::vector<int>& order,
                        bool tip, const std::vector<std::string>& names, const std::string& source,
                        const std::string& where) {
  Eigen::VectorXd values(static_cast<int>(order.size()));
  for (size_t k = 0; k < order.size(); ++k) {
    values(static_cast<int>(k)) =
        CsvNumber(fields[static_cast<size_t>(order[k])], source, where + ", " + names[k]);
  }
  Target target;
  target.time = values(0);
  if (tip) {
    target.kind = TargetKind::kTipPosition;
    target.tip = values.tail<3>();
  } else {
    target.configuration = values.tail<4>();
  }
  return target;
}

// ---- both ----

void CheckTimes(const std::vector<Target>& targets, const std::string& source,
                const std::vector<std::string>& where) {
  if (targets.empty()) Fail(source, "targets", "expected at least one target");
  for (size_t i = 0; i < targets.size(); ++i) {
    if (targets[i].time < 0.0) {
      Fail(source, where[i], "expected a time >= 0 s, got " + Number(targets[i].time));
    }
    if (i > 0 && !(targets[i].time > targets[i - 1].time)) {
      Fail(source, where[i],
           "expected times increasing, got " + Number(targets[i].time) + " s after " +
               Number(targets[i - 1].time) + " s");
    }
  }
}

std::string Location(const std::string& what, size_t index) {
  return what + "[" + std::to_string(index) + "]";
}

}  // namespace

Trajectory ParseTrajectoryYaml(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(source + ": not valid YAML: " + e.what());
  }
  if (!root.IsMap()) Fail(source, "(top level)", "expected a map with targets");
  RejectUnknownKeys(root, {"interpolation", "targets"}, source, "");
  Trajectory trajectory;
  trajectory.interpolate = InterpolationFromYaml(root["interpolation"], source);
  const YAML::Node list = root["targets"];
  if (!list || !list.IsSequence()) Fail(source, "targets", "expected a sequence of targets");
  std::vector<std::string> where;
  for (size_t i = 0; i < list.size(); ++i) {
    where.push_back(Location("targets", i) + ".time");
    trajectory.targets.push_back(TargetFromYaml(list[i], source, Location("targets", i)));
  }
  CheckTimes(trajectory.targets, source, where);
  return trajectory;
}

Trajectory ParseTrajectoryCsv(const std::string& text, const std::string& source) {
  std::stringstream stream(text);
  std::string line;
  std::vector<int> order;
  bool tip = false;
  Trajectory trajectory;
  std::vector<std::string> where;
  for (int number = 1; std::getline(stream, line); ++number) {
    const std::string trimmed = TrimBlanks(line);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    const std::vector<std::string> fields = SplitCsvFields(trimmed);
    const std::string here = "line " + std::to_string(number);
    if (order.empty()) {
      order = ColumnOrder(fields, kConfigurationColumns);
      if (order.empty()) {
        order = ColumnOrder(fields, kTipColumns);
        tip = true;
      }
      if (order.empty()) {
        Fail(source, here,
             "expected a header time,kappa_x,kappa_z,eps0,eps1 or time,tip_x,tip_y,tip_z");
      }
      continue;
    }
    if (fields.size() != order.size()) {
      Fail(source, here,
           "expected " + std::to_string(order.size()) + " columns, got " +
               std::to_string(fields.size()));
    }
    const std::vector<std::string>& names = tip ? kTipColumns : kConfigurationColumns;
    trajectory.targets.push_back(TargetFromCsvRow(fields, order, tip, names, source, here));
    where.push_back(here + ", time");
  }
  if (order.empty()) Fail(source, "line 1", "expected a header and at least one target");
  CheckTimes(trajectory.targets, source, where);
  return trajectory;
}

TargetResolver::TargetResolver(const TendonModel& model, const ControllerOptions& options)
    : model_(model), options_(options) {
  std::string error = options.Validate();
  if (error.empty()) error = options.limits.ValidateFor(model.num_tendons());
  if (!error.empty()) throw std::invalid_argument("controller options: " + error);
}

double TargetResolver::curvature_bound() const {
  return options_.workspace.max_bend_angle / model_.lengths().distal;
}

ResolvedTarget TargetResolver::Resolve(const Target& target) const {
  ResolvedTarget resolved;
  if (!std::isfinite(target.time)) {
    resolved.reason = "time: expected a finite number";
  } else if (target.kind == TargetKind::kConfiguration) {
    resolved = ResolveConfiguration(target.configuration);
  } else if (!target.tip.allFinite()) {
    resolved.reason = "tip: expected finite numbers";
  } else {
    const TipSolution solution =
        ConfigurationForTip(model_, target.tip, options_.limits.min_tension);
    const double strain = solution.configuration(kStrainDistal);
    if (solution.residual > options_.workspace.tip_tolerance) {
      resolved.reason = "tip: unreachable, the nearest reachable tip is " +
                        Number(solution.residual) + " mm away (tip_tolerance " +
                        Number(options_.workspace.tip_tolerance) + " mm)";
    } else if (strain > options_.workspace.max_distal_strain) {
      resolved.reason = "tip: unreachable, it needs the distal section compressed by eps1 " +
                        Number(strain) + ", above workspace.max_distal_strain";
    } else {
      resolved = ResolveConfiguration(solution.configuration);
      resolved.tip_residual = solution.residual;
    }
  }
  resolved.time = target.time;
  return resolved;
}

ResolvedTarget TargetResolver::ResolveConfiguration(const Configuration& q) const {
  ResolvedTarget out;
  const double curvature = q.head<2>().norm();
  const double max_strain = options_.workspace.max_distal_strain;
  if (!q.allFinite()) {
    out.reason = "q: expected finite numbers";
  } else if (curvature > curvature_bound()) {
    out.reason = "curvature " + Number(curvature) + " /mm beyond the bound " +
                 Number(curvature_bound()) + " /mm (workspace.max_bend_angle " +
                 Number(options_.workspace.max_bend_angle) + " rad over the distal length)";
  } else if (q(kStrainDistal) < 0.0 || q(kStrainDistal) > max_strain) {
    out.reason = "eps1 " + Number(q(kStrainDistal)) + ": expected a compression in [0, " +
                 Number(max_strain) + "] (workspace.max_distal_strain)";
  }
  if (!out.reason.empty()) return out;
  const InverseSolution inverse = model_.InverseWithMinimumTension(q, options_.limits.min_tension);
  if (!inverse.feasible) {
    out.reason = "the model has no displacements for it with every tendon taut";
    return out;
  }
  for (int i = 0; i < model_.num_tendons(); ++i) {
    const TendonRange range = options_.limits.RangeOf(i);
    const double y = inverse.displacements(i);
    if (y < range.min || y > range.max) {
      out.reason = "needs tendon " + std::to_string(i) + " at " + Number(y) +
                   " mm, outside its range [" + Number(range.min) + ", " + Number(range.max) +
                   "] mm";
      return out;
    }
  }
  out.configuration = inverse.state.configuration;
  if (out.configuration(kStrainDistal) > max_strain) {
    out.reason = "keeping the tendons taut needs eps1 " + Number(out.configuration(kStrainDistal)) +
                 ", above workspace.max_distal_strain";
    return out;
  }
  out.ok = true;
  out.displacements = inverse.displacements;
  return out;
}

ResolvedTrajectory ResolveTrajectory(const Trajectory& trajectory, const TargetResolver& resolver,
                                     const std::string& source) {
  ResolvedTrajectory out;
  out.interpolate = trajectory.interpolate;
  for (size_t i = 0; i < trajectory.targets.size(); ++i) {
    ResolvedTarget resolved = resolver.Resolve(trajectory.targets[i]);
    if (!resolved.ok) Fail(source, Location("targets", i), resolved.reason);
    out.targets.push_back(std::move(resolved));
  }
  return out;
}

Configuration TargetAt(const ResolvedTrajectory& trajectory, double time) {
  const std::vector<ResolvedTarget>& targets = trajectory.targets;
  if (targets.empty()) throw std::invalid_argument("TargetAt: empty trajectory");
  const auto after =
      std::upper_bound(targets.begin(), targets.end(), time,
                       [](double t, const ResolvedTarget& target) { return t < target.time; });
  if (after == targets.begin()) return targets.front().configuration;
  if (after == targets.end() || !trajectory.interpolate) return std::prev(after)->configuration;
  const ResolvedTarget& before = *std::prev(after);
  const double fraction = (time - before.time) / (after->time - before.time);
  return before.configuration + fraction * (after->configuration - before.configuration);
}

}  // namespace shapesense
