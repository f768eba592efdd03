#pragma once

// A systemd service unit for one shapesense program, as text: what
// `shapesense rig units` writes and deploy/rig/install.sh installs. Type=notify
// (the program says when it is ready and pings the watchdog from its loop,
// runtime/process/systemd_notify.h), restarted on failure within a start
// limit, its output in the journal under its own name.
#include <string>
#include <utility>
#include <vector>

namespace shapesense {

struct UnitSpec {
  // The unit's name without ".service": letters, digits and "_.@-".
  std::string name;
  std::string description;
  // The absolute path of the executable, then its arguments (quoted as
  // systemd needs; "%" and "$" are taken literally).
  std::vector<std::string> command;
  // Absolute; empty: systemd's default (the root directory).
  std::string working_directory;
  // NAME=value pairs; NAME a C identifier.
  std::vector<std::pair<std::string, std::string>> environment;
  // No WATCHDOG=1 for this long and systemd kills and restarts the program.
  double watchdog_s = 5;
  // How long READY=1 may take: carving builds its lookup table first.
  double start_timeout_s = 120;
  int restart_sec_ms = 200;
  // More than start_limit_burst starts within start_limit_interval_s and
  // systemd gives up (the unit fails instead of restarting for ever).
  int start_limit_burst = 5;
  double start_limit_interval_s = 60;
  // The CPUs the program may run on; empty: any.
  std::vector<int> cpu_affinity;
  // 0: the normal scheduler; 1-99: SCHED_FIFO at this priority.
  int realtime_priority = 0;
  // A shapesense program speaks the notify protocol (READY, WATCHDOG); a
  // foreign one (lcm-logger) does not: Type=simple, no watchdog.
  bool notify = true;
  // Units started before this one, besides network-online.target.
  std::vector<std::string> after_units;
};

// The unit file's text. Throws std::invalid_argument naming the field of
// `spec` that is wrong.
std::string FormatUnit(const UnitSpec& spec);

}  // namespace shapesense
