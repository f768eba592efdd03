#include "clients/tools/demo/experiment_faults.h"

#include <algorithm>
#include <sstream>
#include <utility>

#include "libs/core/error.h"

namespace shapesense {
namespace {

constexpr double kLinkDownS = 2.0;

std::vector<std::string> SplitCsvLine(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream stream(line);
  std::string field;
  while (std::getline(stream, field, ',')) fields.push_back(field);
  return fields;
}

size_t ColumnOf(const std::vector<std::string>& header, const std::string& name,
                const std::string& source) {
  const auto found = std::find(header.begin(), header.end(), name);
  if (found == header.end()) throw InputError(source + ": no column '" + name + "'");
  return static_cast<size_t>(found - header.begin());
}

double SecondsBetween(int64_t from_utime, int64_t to_utime) {
  return static_cast<double>(to_utime - from_utime) * 1e-6;
}

}  // namespace

const char* FaultName(FaultKind kind) {
  switch (kind) {
    case FaultKind::kControlLinkDown:
      return "control_link_down";
    case FaultKind::kKillShape:
      return "shape_killed";
    case FaultKind::kRestartLogger:
      return "logger_restarted";
  }
  return "?";
}

std::vector<ExperimentFault> StandardFaults(int targets) {
  std::vector<ExperimentFault> faults = {{FaultKind::kControlLinkDown, 2, 1.0, kLinkDownS},
                                         {FaultKind::kKillShape, 3, 1.0, 0.0},
                                         {FaultKind::kRestartLogger, 4, 1.0, 0.0}};
  faults.resize(std::min<size_t>(faults.size(), static_cast<size_t>(std::max(0, targets - 1))));
  return faults;
}

std::string CheckFaults(const std::vector<ExperimentFault>& faults,
                        const std::vector<ExperimentTarget>& targets) {
  for (size_t i = 0; i < faults.size(); ++i) {
    const ExperimentFault& fault = faults[i];
    const std::string what = "fault " + std::to_string(i + 1) + " (" + FaultName(fault.kind) + ")";
    if (fault.target < 1 || fault.target > static_cast<int>(targets.size())) {
      return what + ": no target " + std::to_string(fault.target);
    }
    const ExperimentTarget& target = targets[static_cast<size_t>(fault.target - 1)];
    // Targets go out a little before they start: the fault must be over by then.
    if (fault.after_s < 0 || fault.duration_s < 0 ||
        target.start_s + fault.after_s + fault.duration_s > target.end_s - 0.5) {
      return what + ": does not end within its target's hold";
    }
    if (i > 0 && fault.target <= faults[i - 1].target) {
      return what + ": faults must come one per target, in order";
    }
  }
  return "";
}

FaultInjector::FaultInjector(std::vector<ExperimentFault> faults, Actions actions)
    : faults_(std::move(faults)), actions_(std::move(actions)) {}

void FaultInjector::Step(double t, const std::vector<ExperimentTarget>& targets,
                         int64_t now_utime) {
  if (link_down_ >= 0) {
    FaultEvent& event = events_[static_cast<size_t>(link_down_)];
    if (SecondsBetween(event.start_utime, now_utime) >= event.fault.duration_s) {
      actions_.set_control_link(true);
      event.end_utime = now_utime;
      link_down_ = -1;
    }
  }
  if (next_ >= faults_.size()) return;
  const ExperimentFault& fault = faults_[next_];
  if (t < targets[static_cast<size_t>(fault.target - 1)].start_s + fault.after_s) return;
  ++next_;
  events_.push_back({fault, now_utime, now_utime});
  switch (fault.kind) {
    case FaultKind::kControlLinkDown:
      actions_.set_control_link(false);
      link_down_ = static_cast<int>(events_.size()) - 1;
      break;
    case FaultKind::kKillShape:
      actions_.kill_shape();
      break;
    case FaultKind::kRestartLogger:
      events_.back().end_utime = actions_.restart_logger();
      break;
  }
}

void FaultInjector::Finish(int64_t now_utime) {
  if (link_down_ < 0) return;
  actions_.set_control_link(true);
  events_[static_cast<size_t>(link_down_)].end_utime = now_utime;
  link_down_ = -1;
}

std::vector<ControllerStep> ParseControllerSteps(const std::string& csv,
                                                 const std::string& source) {
  std::stringstream stream(csv);
  std::string line;
  if (!std::getline(stream, line)) throw InputError(source + ": empty");
  const std::vector<std::string> header = SplitCsvLine(line);
  const size_t utime = ColumnOf(header, "utime", source);
  const size_t mode = ColumnOf(header, "mode", source);
  const size_t sent = ColumnOf(header, "sent", source);
  const size_t age = ColumnOf(header, "sensing_age_s", source);
  const size_t needed = std::max({utime, mode, sent, age}) + 1;
  std::vector<ControllerStep> steps;
  while (std::getline(stream, line)) {
    const std::vector<std::string> fields = SplitCsvLine(line);
    if (fields.size() < needed) continue;  // a row cut short when the program was killed
    steps.push_back(
        {std::stoll(fields[utime]), fields[mode], fields[sent] == "1", std::stod(fields[age])});
  }
  return steps;
}

ControllerConduct JudgeConduct(const std::vector<ControllerStep>& steps, const FaultEvent& event,
                               int64_t until_utime, double hold_age_s) {
  ControllerConduct conduct;
  bool held = false;
  for (const ControllerStep& step : steps) {
    if (step.utime < event.start_utime || step.utime > until_utime) continue;
    ++conduct.steps;
    const double after = SecondsBetween(event.start_utime, step.utime);
    if (step.mode == "hold") {
      ++conduct.held_steps;
      if (conduct.first_hold_after_s < 0) conduct.first_hold_after_s = after;
      held = true;
    } else if (step.mode == "stop") {
      ++conduct.stopped_steps;
      if (conduct.first_stop_after_s < 0) conduct.first_stop_after_s = after;
      held = true;
    } else if (step.sent && held && step.utime >= event.end_utime && conduct.resumed_after_s < 0) {
      conduct.resumed_after_s = SecondsBetween(event.end_utime, step.utime);
    }
    // NaN ages (no sensing yet) compare false: never counted as fresh.
    if (step.sent && !(step.sensing_age_s < hold_age_s)) ++conduct.sent_on_stale;
    conduct.max_sensing_age_s = std::max(conduct.max_sensing_age_s, step.sensing_age_s);
  }
  return conduct;
}

LogContinuity JudgeContinuity(const std::vector<std::vector<int64_t>>& segments) {
  LogContinuity continuity;
  int64_t previous_last = -1;
  for (const std::vector<int64_t>& segment : segments) {
    if (segment.empty()) continue;
    continuity.messages += static_cast<int64_t>(segment.size());
    for (size_t i = 1; i < segment.size(); ++i) {
      continuity.missing_within_runs += std::max<int64_t>(0, segment[i] - segment[i - 1] - 1);
    }
    if (previous_last >= 0) {
      continuity.gap_between_runs += std::max<int64_t>(0, segment.front() - previous_last - 1);
    }
    previous_last = segment.back();
  }
  return continuity;
}

std::vector<std::vector<int64_t>> SplitAt(const std::vector<std::pair<int64_t, int64_t>>& logged,
                                          const std::vector<int64_t>& splits) {
  std::vector<std::vector<int64_t>> segments(splits.size() + 1);
  for (const auto& [utime, sequence] : logged) {
    const auto after = std::upper_bound(splits.begin(), splits.end(), utime);
    segments[static_cast<size_t>(after - splits.begin())].push_back(sequence);
  }
  return segments;
}

double OutageAround(const std::vector<int64_t>& times, int64_t at_utime) {
  for (size_t i = 1; i < times.size(); ++i) {
    if (times[i - 1] <= at_utime && times[i] > at_utime) {
      return SecondsBetween(times[i - 1], times[i]);
    }
  }
  return 0.0;
}

}  // namespace shapesense
