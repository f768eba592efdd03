#pragma once

// `shapesense demo`: the closed-loop experiment on the virtual rig. The
// live pipeline runs as separate programs over LCM with the rig-sim in plant
// mode (the manipulator is a tendon plant 20% off the controller's model,
// with play on its tendons); the shape service senses q. Then
// shapesense-controller drives the plant through the same targets once per
// mode (open loop, then closed loop on the sensed shape), each target held
// for a while. This process is the experimenter: it streams the targets on
// SHAPESENSE_TARGET at their times, records the plant's true q from the
// rig's truth, audits every command that went out against the safety
// limits (LimitAudit) and scores each target's steady-state tip error
// (libs/evaluation/closed_loop_score.h).
//
//   rig-sim --plant ─► capture ─► carving ─► shape (q) ─► controller ─► rig-sim
//        └─ truth (true q) ─────────────────────────────► this process ◄─ commands
//
// Writes out/report.json, out/experiment.txt (the table), out/tip_paths.png,
// out/pipeline.lcm (lcm-logger), out/<mode>/controller_log.{csv,lcmlog},
// out/logs/<program>.log and out/setup/.
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "clients/tools/demo/demo_scorer.h"
#include "clients/tools/demo/experiment_attack.h"
#include "clients/tools/demo/experiment_faults.h"
#include "clients/tools/demo/live_demo.h"
#include "libs/control/limit_audit.h"
#include "libs/evaluation/closed_loop_score.h"
#include "runtime/process/process_group.h"
#include "runtime/process/virtual_hosts.h"

namespace shapesense {

struct ExperimentArgs {
  std::filesystem::path out = "demo-output";
  // rig_plant.yaml, shape_service_plant.yaml, controller_client.yaml and the
  // files they name; empty: the repository's config/ (FindConfigDir).
  std::filesystem::path config_dir;
  double rate_hz = 30.0;  // camera trigger rate
  uint32_t seed = 7;      // synthetic rig and pixel noise
  ExperimentTargetOptions targets;
  double window_s = 1.0;  // steady state: the last this many seconds of each hold
  std::vector<std::string> modes = {"open_loop", "closed_loop"};
  std::string network = "private network namespace";  // for the report
  std::filesystem::path bin_dir;                      // empty: beside this executable
  std::filesystem::path lcm_logger;                   // empty: lcm-logger on $PATH
  DemoProgress progress = DemoProgress::kLines;
  // Three hosts (demo_hosts.h) made by the caller in its private network
  // namespace, their clocks offset as it chose; null: one host.
  const VirtualHosts* hosts = nullptr;
  // Made during the last run; three hosts only (experiment_faults.h).
  std::vector<ExperimentFault> faults;
  // Message authentication: key files, or insecure; neither: a new key in
  // out/setup/rig.key (demo_auth.h).
  AuthOptions auth;
  // The web monitor's listening socket in the host's network (DemoSettings); -1: none.
  int monitor_socket = -1;
  // Runs the attacker (experiment_attack.h) through every run.
  bool attacker = false;
};

// How one fault went (experiment_faults.h).
struct FaultOutcome {
  FaultEvent event;
  double at_s = 0;              // from the run's start
  ControllerConduct conduct;    // from the controller's step log
  double sensing_outage_s = 0;  // shape_killed: the gap in the shapes the operator heard
  int restarts = 0;             // shape_killed: by the supervisor
  LogContinuity log;            // logger_restarted: the truth in its log
};

// What the rig network carried and each host measured (three hosts only).
struct RigNetworkReport {
  std::vector<VirtualHostSpec> hosts;
  std::map<std::string, std::string> addresses;
  std::map<std::string, std::vector<std::string>> programs;  // by host
  // The control host's rig interface over the runs.
  double received_bytes_per_s = 0;
  double sent_bytes_per_s = 0;
  // Every message the operator host heard on the rig network, by channel;
  // how many of them were camera images (must be none).
  std::map<std::string, int64_t> channel_messages;
  int64_t image_messages = 0;
  // Each host's measured offset of every other host's clock, ms (from
  // their status).
  std::map<std::string, std::map<std::string, double>> clock_offsets_ms;
  std::vector<FaultOutcome> faults;
  int releases = 0;  // the operator's e-stop releases after a stop
  // `shapesense rig status --once --json` on the operator host during the
  // last run, and its exit status (0: every expected program up).
  nlohmann::json rig_status;
  std::string rig_status_end;
};

// What one controller run did.
struct ExperimentRun {
  RunScore score;
  std::vector<ConfigurationSample> truth;  // the plant's true q over the run
  LimitViolations violations;              // of the commands it sent
  std::string first_violation;
  int64_t commands = 0;         // audited
  int64_t commands_missed = 0;  // sent but lost on the way to the audit (by step number)
  int64_t shapes = 0;           // sensed shapes with q that arrived during the run
  int targets_sent = 0;
  ProgramEnd end;  // how the controller ended (cleanly, on SIGTERM)
};

struct ExperimentReport {
  std::string network;
  std::string lcm_url;
  double rate_hz = 0.0;
  SectionLengths rest;
  std::vector<ExperimentTarget> targets;  // resolved by the controller's model
  double window_s = 0.0;
  std::vector<ExperimentRun> runs;
  DemoScore sensing;  // the shapes against the truth over the whole experiment
  std::vector<ProgramEnd> programs;
  std::filesystem::path log;
  std::optional<RigNetworkReport> rig;  // three hosts only
  std::string auth;                     // the experimenter's bus: "on (key N)", ...
  std::optional<AttackReport> attack;   // --attacker only
  std::string failure;
  bool interrupted = false;

  // The run of `mode`, nullptr when none.
  const ExperimentRun* Run(const std::string& mode) const;
  int limit_violations() const;
};

// The repository's config/ seen from this executable (build/bin/../../config)
// or from the working directory; empty when neither has rig_plant.yaml.
std::filesystem::path FindConfigDir();

// Runs it; `stop` (Ctrl-C) ends it early, cleanly. Throws ProgramFailure naming
// a program that is missing, failed to start or ended early (report.json
// says so too), InputError on bad arguments or config files.
ExperimentReport RunClosedLoopExperiment(const ExperimentArgs& args, const std::atomic<bool>& stop,
                                         std::ostream& log);

// One run's scores in report.json: {mode, mean_tip_error_mm,
//  max_tip_error_mm, mean_tip_error_percent, targets_scored,
//  targets_within_1mm, targets: [{index, target_q, target_tip_mm, mean_tip_mm,
//  tip_error_mm, max_tip_error_mm, distal_tip_error_mm, samples}]}
nlohmann::json RunScoreToJson(const RunScore& run);

// report.json: open_loop_tip_error_mm, closed_loop_tip_error_mm (means over
// the targets at steady state), limit_violations, and every run's scores.
nlohmann::json ExperimentReportToJson(const ExperimentReport& report);

}  // namespace shapesense
