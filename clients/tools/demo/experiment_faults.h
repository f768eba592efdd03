#pragma once

// Faults the closed-loop experiment can inject on three hosts
// (`shapesense demo --hosts 3 --faults`, demo_hosts.h), and what is judged
// of each afterwards from the controller's own step log and the logger's
// files (issue 13; docs/rig.md, "When something fails"):
//
//   control link down   the control host's cable pulled at the switch for
//                       2 s: the controller holds once its sensing is older
//                       than hold_age, stops once it is older than lost_age,
//                       and moves again only after the operator's release
//                       (this process re-arms it once fresh shapes come);
//   shape killed        SIGKILL to the shape service, which its supervisor
//                       (the group's restart, standing in for systemd's
//                       Restart=on-failure) starts again: the outage is
//                       the gap between the shapes on either side;
//   logger restarted    the operator's lcm-logger stopped and started again
//                       (with --rotate it goes on in the same file): its
//                       log keeps every frame-set's truth before and after,
//                       and the frame-sets in between are the counted gap.
//
// Each fault starts `after_s` into the hold of its target, so that no
// target goes out while it lasts.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "libs/evaluation/closed_loop_score.h"

namespace shapesense {

enum class FaultKind { kControlLinkDown, kKillShape, kRestartLogger };
const char* FaultName(FaultKind kind);  // "control_link_down", "shape_killed", "logger_restarted"

struct ExperimentFault {
  FaultKind kind = FaultKind::kControlLinkDown;
  int target = 1;         // 1-based: during this target's hold
  double after_s = 1.0;   // into the hold
  double duration_s = 0;  // the link's time down (the others are instants)
};

// One of each, on targets 2, 3 and 4 (fewer targets: as many as fit).
std::vector<ExperimentFault> StandardFaults(int targets);
// Empty, or why the faults do not fit the targets.
std::string CheckFaults(const std::vector<ExperimentFault>& faults,
                        const std::vector<ExperimentTarget>& targets);

// When a fault was made (µs, this process's clock).
struct FaultEvent {
  ExperimentFault fault;
  int64_t start_utime = 0;
  // The link back up; the logger between its stop and its start; = start
  // for the kill.
  int64_t end_utime = 0;
};

// Makes the faults at their times in a run; the actions do the deed.
class FaultInjector {
 public:
  struct Actions {
    std::function<void(bool up)> set_control_link;
    std::function<void()> kill_shape;
    // Returns when (µs) the old logger had stopped and the new one not begun.
    std::function<int64_t()> restart_logger;
  };
  FaultInjector(std::vector<ExperimentFault> faults, Actions actions);

  // `t`: seconds from the run's origin; `now_utime`: this process's clock.
  void Step(double t, const std::vector<ExperimentTarget>& targets, int64_t now_utime);
  // Brings the link back up if the run ended with it down.
  void Finish(int64_t now_utime);
  const std::vector<FaultEvent>& events() const { return events_; }

 private:
  std::vector<ExperimentFault> faults_;
  Actions actions_;
  std::vector<FaultEvent> events_;
  size_t next_ = 0;
  int link_down_ = -1;  // the event of the link now down
};

// One step of the controller's CSV log (services/controller/controller_log.h).
struct ControllerStep {
  int64_t utime = 0;
  std::string mode;  // open_loop, closed_loop, model_less, hold, stop
  bool sent = false;
  double sensing_age_s = 0;
};
// Parses the CSV text; InputError naming `source` when a column is missing.
std::vector<ControllerStep> ParseControllerSteps(const std::string& csv, const std::string& source);

// What the controller did around one fault, from its steps.
struct ControllerConduct {
  int64_t steps = 0;          // from the fault's start to `until`
  int64_t held_steps = 0;     // mode hold
  int64_t stopped_steps = 0;  // mode stop
  int64_t sent_on_stale = 0;  // commands sent with sensing >= hold_age: must be 0
  double max_sensing_age_s = 0;
  double first_hold_after_s = -1;  // from the fault's start (-1: none)
  double first_stop_after_s = -1;
  // The first command sent after it held or stopped, from the fault's end (-1: none).
  double resumed_after_s = -1;
};
ControllerConduct JudgeConduct(const std::vector<ControllerStep>& steps, const FaultEvent& event,
                               int64_t until_utime, double hold_age_s);

// Every frame-set's truth in the logger's files: `segments` is each
// logger's run (split at its restarts) with the trigger sequence numbers it
// logged, in order.
struct LogContinuity {
  int64_t messages = 0;
  int64_t missing_within_runs = 0;  // frame-sets a running logger missed: must be 0
  int64_t gap_between_runs = 0;     // frame-sets between one run's last and the next's first
};
LogContinuity JudgeContinuity(const std::vector<std::vector<int64_t>>& segments);

// A log's (receive time, sequence number) pairs split at `splits` (µs,
// increasing): one segment per interval.
std::vector<std::vector<int64_t>> SplitAt(const std::vector<std::pair<int64_t, int64_t>>& logged,
                                          const std::vector<int64_t>& splits);

// The largest gap between consecutive times (µs) that spans `at_utime`, s;
// 0 when none does.
double OutageAround(const std::vector<int64_t>& times, int64_t at_utime);

}  // namespace shapesense
