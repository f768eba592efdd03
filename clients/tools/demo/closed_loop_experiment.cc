#include "clients/tools/demo/closed_loop_experiment.h"
#include "clients/tools/demo/demo_auth.h"

#include <chrono>
#include <cstdio>
#include <exception>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <set>
#include <thread>
#include <utility>

#include "clients/tools/demo/demo_hosts.h"
#include "clients/tools/demo/demo_session.h"
#include "clients/tools/demo/experiment_hosts.h"
#include "libs/control/targets.h"
#include "libs/core/error.h"
#include "libs/evaluation/closed_loop_plot.h"
#include "libs/mechanics/configuration_geometry.h"
#include "libs/sim/scene_generators.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/shape_message.h"
#include "services/controller/controller_config.h"
#include "shapesense/configuration_target_t.hpp"
#include "shapesense/estop_t.hpp"
#include "shapesense/tendon_command_t.hpp"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

// Targets go out this long before they take effect, carrying their start
// time: the controller applies them on the dot, however late LCM is.
constexpr double kPublishAheadS = 0.3;
// The first target's clock starts this long after the controller is up.
constexpr double kRunStartDelayS = 0.5;
constexpr double kProgressPeriodS = 5.0;
// The operator releases a stopped controller once shapes this fresh come,
// and not more often than every kReleasePeriodS.
constexpr int64_t kFreshShapeUs = 300'000;
constexpr int64_t kReleasePeriodUs = 500'000;
// `rig status` is asked this long into the last run (the controller is up).
constexpr double kRigStatusAtS = 3.0;

struct ExperimentFiles {
  fs::path plant;       // the rig-sim's --plant
  fs::path shape;       // the shape service's --config
  fs::path controller;  // the controller service's --config
};

ExperimentFiles FindFiles(const ExperimentArgs& args) {
  const fs::path dir = args.config_dir.empty() ? FindConfigDir() : args.config_dir;
  if (dir.empty()) {
    throw InputError(
        "the closed-loop experiment needs the repository's config/ folder (rig_plant.yaml, "
        "shape_service_plant.yaml, controller_client.yaml): run it from the repository, or "
        "give --config-dir");
  }
  ExperimentFiles files{fs::absolute(dir / "rig_plant.yaml"),
                        fs::absolute(dir / "shape_service_plant.yaml"),
                        fs::absolute(dir / "controller_client.yaml")};
  for (const fs::path& file : {files.plant, files.shape, files.controller}) {
    if (!fs::exists(file)) throw InputError(file.string() + ": not found");
  }
  return files;
}

// The controller's own view: its model, limits and target resolution.
struct ControllerView {
  ControllerSetup setup;
  TendonModel model;
  explicit ControllerView(const fs::path& config)
      : setup(LoadControllerSetup(config, StreamOverrides())), model(setup.manipulator) {}

  static ControllerOverrides StreamOverrides() {
    ControllerOverrides overrides;
    overrides.targets = "stream";
    return overrides;
  }
};

// The experiment's targets as the controller resolves them (eps1 raised to
// keep the tendons taut, eps0 the one that follows): what it aims at.
std::vector<ExperimentTarget> ResolveTargets(const ExperimentArgs& args,
                                             const ControllerView& view) {
  std::vector<ExperimentTarget> targets = MakeExperimentTargets(args.targets, view.model.lengths());
  const TargetResolver resolver(view.model, view.setup.controller);
  for (size_t i = 0; i < targets.size(); ++i) {
    Target target;
    target.configuration = targets[i].q;
    const ResolvedTarget resolved = resolver.Resolve(target);
    if (!resolved.ok) {
      throw InputError("experiment target " + std::to_string(i + 1) + ": " + resolved.reason);
    }
    targets[i].q = resolved.configuration;
  }
  return targets;
}

DemoSettings MakeSettings(const ExperimentArgs& args, const Rig& rig, const ExperimentFiles& files,
                          double run_s) {
  DemoSettings settings =
      BaseDemoSettings(args.bin_dir, args.lcm_logger, args.out, rig, args.rate_hz, args.seed);
  settings.cameras = DemoCameras::kGigE;  // the plant lives in the rig-sim
  settings.duration_s = run_s * static_cast<double>(args.modes.size());
  settings.plant_config = files.plant;
  settings.shape_config = files.shape;
  settings.log_channels = kControlChannels;  // images would be gigabytes
  settings.monitor_socket = args.monitor_socket;
  return settings;
}

double RunSeconds(const ExperimentArgs& args) {
  return args.targets.first_start_s + args.targets.hold_s * args.targets.count;
}

// What this process hears: the truth, the shapes, the commands and every
// status; while a run records, its samples and its audit.
class ExperimentListener {
 public:
  ExperimentListener(LcmBus& bus, DemoScorer& scorer, SafetyEnvelope envelope)
      : scorer_(scorer), envelope_(std::move(envelope)), audit_(envelope_) {
    bus.Subscribe<shape_t>(channels::kTruth,
                           [this](shape_t&& truth, const std::string&, int64_t receive_utime) {
                             OnTruth(truth, receive_utime);
                           });
    bus.Subscribe<shape_t>(channels::kShape, [this](shape_t&& shape, const std::string&,
                                                    int64_t utime) { OnShape(shape, utime); });
    bus.Subscribe<tendon_command_t>(
        channels::kTendonCommand,
        [this](tendon_command_t&& command, const std::string&, int64_t) { OnCommand(command); });
    bus.Subscribe<service_status_t>(channels::kStatusPattern,
                                    [this](service_status_t&& status, const std::string&, int64_t) {
                                      scorer_.AddStatus(status);
                                      seen_.insert(status.service);
                                      if (status.num_clock_offsets > 0) {
                                        by_host_[status.header.host] = std::move(status);
                                      }
                                    });
  }

  // Records for `run` from now on, the controller's first commands
  // included; its controller's status is not seen yet.
  void BeginRun(ExperimentRun* run) {
    run_ = run;
    audit_ = LimitAudit(envelope_);
    truth_.clear();
    shape_times_.clear();
    seen_.erase("controller");
  }
  // Ends the recording: the truth's times become seconds from `origin_utime`.
  void EndRun(int64_t origin_utime) {
    if (run_ == nullptr) return;
    for (const auto& [utime, q] : truth_) {
      run_->truth.push_back({static_cast<double>(utime - origin_utime) * 1e-6, q});
    }
    run_->violations = audit_.violations();
    run_->first_violation = audit_.first_violation();
    run_->commands = audit_.commands();
    run_->commands_missed = audit_.missed();
    run_ = nullptr;
  }
  bool StatusSeen(const std::string& service) const { return seen_.contains(service); }
  // When the run's shapes with q arrived (this clock, µs).
  const std::vector<int64_t>& ShapeTimes() const { return shape_times_; }
  // The controller's newest command was a stop, and a shape has come since
  // `fresh_us` (µs, this clock): what the operator waits for to release it.
  bool StoppedWithFreshSensing(int64_t now_utime, int64_t fresh_us) const {
    return last_mode_ == tendon_command_t::MODE_STOP && !shape_times_.empty() &&
           now_utime - shape_times_.back() < fresh_us;
  }
  // Each host's newest status that carries clock offsets.
  const std::map<std::string, service_status_t>& StatusByHost() const { return by_host_; }
  // The newest true configuration of the run, as ConfigurationSample with
  // the time from `origin_utime`; nullopt before any.
  std::optional<ConfigurationSample> Latest(int64_t origin_utime) const {
    if (truth_.empty()) return std::nullopt;
    const auto& [utime, q] = truth_.back();
    return ConfigurationSample{static_cast<double>(utime - origin_utime) * 1e-6, q};
  }

 private:
  // The truth is dated on this clock (its receive time less its age), as the
  // targets are: never by the virtual rig's trigger time, which is another
  // host's clock on a rig of several.
  void OnTruth(const shape_t& truth, int64_t receive_utime) {
    scorer_.AddTruth(truth);
    const std::optional<Configuration> q = MessageConfiguration(truth);
    if (run_ != nullptr && q) truth_.emplace_back(receive_utime - truth.header.data_age_us, *q);
  }
  void OnShape(const shape_t& shape, int64_t utime) {
    scorer_.AddShape(shape, utime);
    if (run_ == nullptr || !shape.has_configuration) return;
    ++run_->shapes;
    shape_times_.push_back(utime);
  }
  void OnCommand(const tendon_command_t& command) {
    if (run_ == nullptr) return;
    last_mode_ = command.mode;
    audit_.Check(Eigen::Map<const Eigen::VectorXd>(
                     command.displacement_mm.data(),
                     static_cast<Eigen::Index>(command.displacement_mm.size())),
                 command.header.utime, command.header.seq);
  }

  DemoScorer& scorer_;
  const SafetyEnvelope envelope_;
  LimitAudit audit_;
  ExperimentRun* run_ = nullptr;
  std::vector<std::pair<int64_t, Configuration>> truth_;  // by trigger time, µs
  std::vector<int64_t> shape_times_;
  int8_t last_mode_ = tendon_command_t::MODE_HOLD;
  std::set<std::string> seen_;
  std::map<std::string, service_status_t> by_host_;
};

// The index of the target in force at `time_s`, -1 before the first.
int TargetAt(const std::vector<ExperimentTarget>& targets, double time_s) {
  for (size_t i = targets.size(); i-- > 0;) {
    if (time_s >= targets[i].start_s) return static_cast<int>(i);
  }
  return -1;
}

Vec3 TipOf(const Configuration& q, const SectionLengths& rest) {
  return BaseFromTip(q, rest).translation();
}

configuration_target_t TargetMessage(const ExperimentTarget& target, int64_t origin_utime,
                                     int index) {
  configuration_target_t message{};
  message.header.seq = index;
  message.header.utime = NowUtime();
  message.kind = configuration_target_t::KIND_CONFIGURATION;
  for (int i = 0; i < 4; ++i) message.q[i] = target.q(i);
  message.duration_s = 0.0;
  message.start_utime = origin_utime + static_cast<int64_t>(target.start_s * 1e6);
  message.source = "shapesense demo";
  return message;
}

void PrintProgress(const ExperimentReport& report, const std::string& mode, double t,
                   const std::optional<ConfigurationSample>& latest, std::ostream& log) {
  const int target = TargetAt(report.targets, t);
  const int at_sample = latest ? TargetAt(report.targets, latest->time_s) : -1;
  char error[32] = "-";
  if (at_sample >= 0) {
    const Configuration& goal = report.targets[static_cast<size_t>(at_sample)].q;
    std::snprintf(error, sizeof(error), "%.3f",
                  (TipOf(latest->q, report.rest) - TipOf(goal, report.rest)).norm());
  }
  char line[160];
  std::snprintf(line, sizeof(line), "  %s %5.1f s: target %d/%zu, true tip %s mm from it",
                mode.c_str(), t, target + 1, report.targets.size(), error);
  log << line << std::endl;
}

// What a run does besides its targets: faults (three hosts), the
// operator's release of a stopped controller, the rig's status.
struct RunExtras {
  FaultInjector* faults = nullptr;
  bool ask_rig_status = false;
};

// One controller run: start it, stream the targets, record, stop it.
class RunDriver {
 public:
  RunDriver(const ExperimentArgs& args, const DemoSettings& settings, const fs::path& controller,
            const HostLayout& layout, ProcessGroup& processes, LcmBus& bus,
            ExperimentListener& listener, const std::atomic<bool>& stop, std::ostream& log)
      : args_(args),
        settings_(settings),
        controller_(controller),
        layout_(layout),
        processes_(processes),
        bus_(bus),
        listener_(listener),
        stop_(stop),
        log_(log) {}

  // False when stopped meanwhile.
  bool Run(const std::string& mode, ExperimentReport& report, ExperimentRun& run,
           const RunExtras& extras) {
    ProgramSpec process = ControllerRun(settings_, controller_, mode, settings_.out / mode);
    layout_.Place(&process);
    fs::create_directories(settings_.out / mode);
    listener_.BeginRun(&run);
    log_ << "  starting " << process.name << std::endl;
    if (!processes_.Start(process, kDemoStartTimeout)) return false;
    origin_ = NowUtime() + static_cast<int64_t>(kRunStartDelayS * 1e6);
    const bool finished = Stream(mode, report, run, extras);
    if (extras.faults != nullptr) extras.faults->Finish(NowUtime());
    run.end = processes_.Stop(process.name);
    listener_.EndRun(origin_);
    run.score = ScoreRun(mode, report.targets, run.truth, report.rest, args_.window_s);
    if (extras.ask_rig_status) CollectRigStatus(report);
    return finished;
  }
  int64_t origin() const { return origin_; }
  int releases() const { return releases_; }

 private:
  bool Stream(const std::string& mode, const ExperimentReport& report, ExperimentRun& run,
              const RunExtras& extras) {
    const double end_s = report.targets.back().end_s;
    double next_progress = kProgressPeriodS;
    bool asked = !extras.ask_rig_status;
    for (;;) {
      const int64_t now = NowUtime();
      const double t = static_cast<double>(now - origin_) * 1e-6;
      if (stop_) return false;
      if (t >= end_s) return true;
      while (run.targets_sent < static_cast<int>(report.targets.size()) &&
             report.targets[static_cast<size_t>(run.targets_sent)].start_s - kPublishAheadS <= t) {
        const auto& target = report.targets[static_cast<size_t>(run.targets_sent)];
        bus_.Publish(channels::kTarget, TargetMessage(target, origin_, run.targets_sent));
        ++run.targets_sent;
      }
      if (extras.faults != nullptr) extras.faults->Step(t, report.targets, now);
      ReleaseIfStopped(now);
      if (!asked && t >= kRigStatusAtS) {
        processes_.Launch(layout_.RigStatus(settings_.bin_dir / "shapesense"));
        asked = true;
      }
      Pump(bus_, 20);
      processes_.CheckRunning();
      if (args_.progress != DemoProgress::kOff && t >= next_progress) {
        next_progress += kProgressPeriodS;
        PrintProgress(report, mode, t, listener_.Latest(origin_), log_);
      }
    }
  }

  // The operator re-arms a controller that stopped (sensing lost) once
  // fresh shapes come again: SHAPESENSE_ESTOP released (docs/controller.md).
  void ReleaseIfStopped(int64_t now) {
    if (!listener_.StoppedWithFreshSensing(now, kFreshShapeUs)) return;
    if (now - last_release_ < kReleasePeriodUs) return;
    estop_t release{};
    release.header.utime = now;
    release.engaged = false;
    release.reason = "sensing is back";
    release.source = "shapesense demo (operator)";
    bus_.Publish(channels::kEstop, release);
    last_release_ = now;
    ++releases_;
    log_ << "  the controller stopped; sensing is back: released it" << std::endl;
  }

  void CollectRigStatus(ExperimentReport& report) {
    const ProgramEnd end = processes_.Stop("rig-status");
    if (!report.rig) return;
    report.rig->rig_status_end = end.how;
    report.rig->rig_status = LastJson(settings_.out / "logs" / "rig-status.log");
  }

  const ExperimentArgs& args_;
  const DemoSettings& settings_;
  const fs::path controller_;
  const HostLayout& layout_;
  ProcessGroup& processes_;
  LcmBus& bus_;
  ExperimentListener& listener_;
  const std::atomic<bool>& stop_;
  std::ostream& log_;
  int64_t origin_ = 0;
  int64_t last_release_ = 0;
  int releases_ = 0;
};

void CheckArgs(const ExperimentArgs& args) {
  if (!(args.rate_hz >= 5.0 && args.rate_hz <= 300.0)) {
    throw InputError("--rate: expected Hz in [5, 300], got " + std::to_string(args.rate_hz));
  }
  if (const std::string error = args.targets.Validate(); !error.empty()) {
    throw InputError("targets: " + error);
  }
  if (!(args.window_s > 0.0 && args.window_s < args.targets.hold_s)) {
    throw InputError("steady-state window: expected 0 < window < hold (" +
                     std::to_string(args.targets.hold_s) + " s), got " +
                     std::to_string(args.window_s));
  }
  for (const std::string& mode : args.modes) {
    ControlMode parsed{};
    if (!ParseControlMode(mode, &parsed)) throw InputError("mode '" + mode + "': unknown");
  }
  if (!args.faults.empty() && args.hosts == nullptr) {
    throw InputError("faults: they act on the hosts' links and programs (--hosts 3)");
  }
}

// Every truth sample of a run with its target: out/<mode>/tip_path.csv.
std::string TipPathCsv(const ExperimentReport& report, const ExperimentRun& run) {
  std::string csv =
      "time_s,target,kappa_x,kappa_z,eps0,eps1,tip_x,tip_y,tip_z,target_tip_x,target_tip_y,"
      "target_tip_z,tip_error_mm\n";
  char row[400];
  for (const ConfigurationSample& sample : run.truth) {
    const int index = TargetAt(report.targets, sample.time_s);
    if (index < 0) continue;
    const Vec3 tip = TipOf(sample.q, report.rest);
    const Vec3 goal = TipOf(report.targets[static_cast<size_t>(index)].q, report.rest);
    std::snprintf(row, sizeof(row),
                  "%.4f,%d,%.9g,%.9g,%.9g,%.9g,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f\n", sample.time_s,
                  index + 1, sample.q(0), sample.q(1), sample.q(2), sample.q(3), tip.x(), tip.y(),
                  tip.z(), goal.x(), goal.y(), goal.z(), (tip - goal).norm());
    csv += row;
  }
  return csv;
}

void WriteOutputs(const ExperimentReport& report, const fs::path& out, std::ostream& log) {
  for (const ExperimentRun& run : report.runs) {
    fs::create_directories(out / run.score.mode);
    WriteFileAtomically(out / run.score.mode / "tip_path.csv", TipPathCsv(report, run));
  }
  std::vector<RunScore> scores;
  std::vector<ExperimentPlotRun> plotted;
  for (const ExperimentRun& run : report.runs) scores.push_back(run.score);
  for (size_t i = 0; i < report.runs.size(); ++i) {
    plotted.push_back(
        {report.runs[i].score.mode, TipPath(report.runs[i].truth, report.rest), &scores[i]});
  }
  const std::string table = FormatExperimentTable(report.targets, scores, report.rest);
  WriteFileAtomically(out / "experiment.txt", table);
  if (!report.targets.empty() && !plotted.empty()) {
    const cv::Mat plot = DrawExperimentPlot(report.targets, plotted, report.rest);
    if (!cv::imwrite((out / "tip_paths.png").string(), plot)) {
      log << "demo: could not write " << (out / "tip_paths.png").string() << std::endl;
    }
  }
  WriteFileAtomically(out / "report.json", ExperimentReportToJson(report).dump(2) + "\n");
  log << "\n" << table;
}

void PrintRunSummary(const ExperimentRun& run, std::ostream& log) {
  log << "  " << run.score.mode << ": mean steady-state tip error " << run.score.mean_tip_error_mm
      << " mm (" << run.score.mean_tip_error_percent << "% of L1), " << run.score.targets_scored
      << " targets scored, " << run.commands << " commands audited, " << run.violations.total()
      << " limit violations"
      << (run.first_violation.empty() ? "" : " (first: " + run.first_violation + ")")
      << "; controller " << run.end.how << std::endl;
}

// Everything a run needs besides its settings.
struct ExperimentParts {
  const DemoPlan& plan;
  const DemoSettings& settings;
  const ExperimentFiles& files;
  const HostLayout& layout;
  ProcessGroup& processes;
  LcmBus& bus;
  ExperimentListener& listener;
  const AttackWitness* witness;  // --attacker only
};

// The backgrounds, the pipeline, then one controller run per mode (the
// faults during the last); false when stopped before the end.
void PrintAttack(const AttackReport& attack, std::ostream& log) {
  log << "attack: " << attack.sent << " forged or replayed messages sent, " << attack.rejected
      << " rejected (";
  const char* separator = "";
  for (const auto& [reason, count] : attack.rejected_by_reason) {
    log << separator << reason << " " << count;
    separator = ", ";
  }
  log << "), " << attack.accepted << " accepted" << std::endl;
  if (!attack.error.empty()) log << "attack: " << attack.error << std::endl;
}

bool RunPhases(const ExperimentArgs& args, const ExperimentParts& parts,
               const std::atomic<bool>& stop, ExperimentReport& report, std::ostream& log) {
  log << "backgrounds: the rig showing its backdrop alone" << std::endl;
  if (!StartAll(parts.processes, parts.plan.background, log)) return false;
  parts.processes.StopAll();
  log << "live pipeline, the rig in plant mode, logged to " << parts.plan.log.string() << std::endl;
  if (!StartAll(parts.processes, parts.plan.pipeline, log)) return false;
  PrintMonitorUrl(parts.settings.monitor_socket, log);
  RigNetworkWatch watch(parts.layout);
  watch.Begin();
  RunDriver driver(args, parts.settings, parts.files.controller, parts.layout, parts.processes,
                   parts.bus, parts.listener, stop, log);
  FaultInjector faults = MakeFaultInjector(args, parts.plan, parts.processes);
  const fs::path attack_report = parts.settings.out / "attack.json";
  if (parts.witness != nullptr) {
    fs::remove(attack_report);
    ProgramSpec attacker = AttackerProgram(parts.settings, attack_report);
    parts.layout.Place(&attacker);
    std::erase_if(attacker.environment,
                  [](const auto& v) { return v.first == "SHAPESENSE_KEY_FILES"; });
    log << "the attacker joins the rig network" << std::endl;
    if (!parts.processes.Start(attacker, kDemoStartTimeout)) return false;
  }
  for (size_t i = 0; i < args.modes.size(); ++i) {
    const std::string& mode = args.modes[i];
    const bool last = i + 1 == args.modes.size();
    log << mode << ": " << report.targets.size() << " targets, " << args.targets.hold_s << " s each"
        << (last && !args.faults.empty() ? ", with faults" : "") << std::endl;
    report.runs.emplace_back();
    const RunExtras extras{last && !args.faults.empty() ? &faults : nullptr,
                           last && parts.layout.active()};
    if (!driver.Run(mode, report, report.runs.back(), extras)) return false;
    PrintRunSummary(report.runs.back(), log);
    if (extras.faults != nullptr) {
      const FaultEvidence evidence{
          parts.settings.out / mode / "controller_log.csv", parts.listener.ShapeTimes(),
          parts.processes.restarts("shape"),
          ControllerView(parts.files.controller).setup.controller.watchdog.hold_age,
          driver.origin(),
          // The last hold's end: the controller's own stop after it is no fault's doing.
          driver.origin() + static_cast<int64_t>(report.targets.back().end_s * 1e6)};
      JudgeFaults(faults, evidence, *report.rig);
    }
  }
  if (parts.witness != nullptr) {
    parts.processes.Stop("attacker");
    report.attack = parts.witness->Judge(attack_report);
    PrintAttack(*report.attack, log);
  }
  if (report.rig) {
    watch.End(*report.rig);
    report.rig->clock_offsets_ms = MeasuredClockOffsetsMs(parts.listener.StatusByHost());
    report.rig->releases = driver.releases();
  }
  return true;
}

nlohmann::json RunToJson(const ExperimentRun& run) {
  nlohmann::json json = RunScoreToJson(run.score);
  json["limit_violations"] = run.violations.total();
  json["limit_violations_by_kind"] = {{"range_or_tension", run.violations.range_or_tension},
                                      {"rate", run.violations.rate},
                                      {"malformed", run.violations.malformed}};
  json["first_violation"] = run.first_violation;
  json["commands_audited"] = run.commands;
  json["commands_missed_by_the_audit"] = run.commands_missed;
  json["sensed_shapes"] = run.shapes;
  json["truth_samples"] = run.truth.size();
  json["targets_sent"] = run.targets_sent;
  json["controller"] = {{"how", run.end.how}, {"clean", run.end.clean}};
  return json;
}

nlohmann::json MeanError(const ExperimentReport& report, const std::string& mode) {
  const ExperimentRun* run = report.Run(mode);
  if (run == nullptr || run->score.targets_scored == 0) return nullptr;
  return run->score.mean_tip_error_mm;
}

}  // namespace

nlohmann::json RunScoreToJson(const RunScore& run) {
  const auto array = [](const auto& v) {
    return std::vector<double>(v.data(), v.data() + v.size());
  };
  nlohmann::json targets = nlohmann::json::array();
  for (const TargetScore& t : run.targets) {
    targets.push_back({{"index", t.index},
                       {"target_q", array(t.target_q)},
                       {"target_tip_mm", array(t.target_tip)},
                       {"mean_tip_mm", array(t.mean_tip)},
                       {"tip_error_mm", t.tip_error_mm},
                       {"max_tip_error_mm", t.max_tip_error_mm},
                       {"distal_tip_error_mm", t.distal_tip_error_mm},
                       {"samples", t.samples}});
  }
  return {{"mode", run.mode},
          {"mean_tip_error_mm", run.mean_tip_error_mm},
          {"max_tip_error_mm", run.max_tip_error_mm},
          {"mean_tip_error_percent", run.mean_tip_error_percent},
          {"targets_scored", run.targets_scored},
          {"targets_within_1mm", run.targets_within(1.0)},
          {"targets", targets}};
}

nlohmann::json ExperimentReportToJson(const ExperimentReport& report) {
  nlohmann::json json;
  json["provenance"] = ProvenanceToJson();
  json["open_loop_tip_error_mm"] = MeanError(report, "open_loop");
  json["closed_loop_tip_error_mm"] = MeanError(report, "closed_loop");
  json["limit_violations"] = report.limit_violations();
  json["distal_length_mm"] = report.rest.distal;
  json["targets"] = report.targets.size();
  json["hold_s"] =
      report.targets.empty() ? 0.0 : report.targets[0].end_s - report.targets[0].start_s;
  json["steady_state_window_s"] = report.window_s;
  json["network"] = report.network;
  json["lcm_url"] = report.lcm_url;
  json["rate_hz"] = report.rate_hz;
  json["runs"] = nlohmann::json::array();
  for (const ExperimentRun& run : report.runs) json["runs"].push_back(RunToJson(run));
  const LiveScorer::Report& live = report.sensing.live;
  json["sensing"] = {{"frame_sets_rendered", live.truths},
                     {"shapes", live.shapes},
                     {"valid_shapes", live.valid_shapes},
                     {"centerline_rms_mean_mm", live.centerline_rms_mean},
                     {"centerline_rms_max_mm", live.centerline_rms_max},
                     {"tip_error_mean_mm", live.tip_error_mean},
                     {"tip_error_max_mm", live.tip_error_max},
                     {"trigger_to_shape_p50_ms", live.trigger_to_shape_ms.p50}};
  json["log"] = report.log.string();
  if (report.rig) AddRigToJson(*report.rig, json);
  json["auth"] = report.auth;
  if (report.attack) json["attack"] = AttackReportToJson(*report.attack);
  json["programs"] = ProgramsToJson(report.programs);
  json["failure"] = report.failure;
  json["interrupted"] = report.interrupted;
  return json;
}

const ExperimentRun* ExperimentReport::Run(const std::string& mode) const {
  for (const ExperimentRun& run : runs) {
    if (run.score.mode == mode) return &run;
  }
  return nullptr;
}

int ExperimentReport::limit_violations() const {
  int total = 0;
  for (const ExperimentRun& run : runs) total += run.violations.total();
  return total;
}

fs::path FindConfigDir() {
  for (const fs::path& dir :
       {ExecutableDir() / ".." / ".." / "config", fs::current_path() / "config"}) {
    std::error_code error;
    if (fs::exists(dir / "rig_plant.yaml", error)) return fs::weakly_canonical(dir, error);
  }
  return {};
}

namespace {

// The experiment on this thread's network (with three hosts, the operator
// host's).
ExperimentReport RunExperimentHere(const ExperimentArgs& args, const std::atomic<bool>& stop,
                                   std::ostream& log) {
  CheckArgs(args);
  ExperimentFiles files = FindFiles(args);
  SyntheticRigOptions rig_options;
  rig_options.seed = args.seed;
  const Rig rig = MakeSyntheticRig(rig_options);
  DemoSettings settings = MakeSettings(args, rig, files, RunSeconds(args));
  settings.auth = PrepareDemoAuth(args.auth, settings.out / "setup", log);
  if (args.hosts != nullptr) {
    files.controller =
        ControllerConfigForHosts(files.controller, settings.out / "setup" / "config");
    settings.lcm_url = kDemoRigNetworkUrl;
  }
  const ControllerView view(files.controller);
  DemoPlan plan = MakeDemoPlan(settings);
  ExperimentReport report;
  report.network = args.network;
  report.lcm_url = settings.lcm_url;
  report.rate_hz = args.rate_hz;
  report.rest = view.model.lengths();
  report.targets = ResolveTargets(args, view);
  report.window_s = args.window_s;
  report.log = plan.log;
  if (const std::string error = CheckFaults(args.faults, report.targets); !error.empty()) {
    throw InputError(error);
  }
  ThrowIfMissing(plan);
  WarnIfSocketBuffersAreSmall(log);
  PrepareOutput(plan, rig);
  const HostLayout layout(args, settings.out / "setup", settings.camera_names, settings.auth);
  if (layout.active()) {
    RotateLogs(plan);
    for (ProgramSpec& process : plan.background) layout.Place(&process);
    for (ProgramSpec& process : plan.pipeline) layout.Place(&process);
    for (ProgramSpec& process : plan.pipeline) process.restart = process.name == "shape";
    report.rig = DescribeHosts(*args.hosts, plan, args.modes);
  }
  LcmBusOptions bus_options = LcmBusOptions::FromEnvironment(settings.lcm_url);
  bus_options.auth = settings.auth;
  if (layout.active()) {
    bus_options.local_url = kDemoLcmUrl;
    bus_options.host = kOperatorHostName;
  }
  LcmBus bus(bus_options);
  DemoScorer scorer;
  ExperimentListener listener(bus, scorer,
                              SafetyEnvelope(view.model, view.setup.controller.limits));
  report.auth = bus.AuthSnapshot().mode;
  std::optional<AttackWitness> witness;
  if (args.attacker) witness.emplace(bus);
  ProcessGroup processes(
      plan.logs_dir, stop,
      {[&bus](int ms) { Pump(bus, ms); },
       [&listener](const std::string& service) { return listener.StatusSeen(service); }});
  const ExperimentParts parts{plan,      settings, files,    layout,
                              processes, bus,      listener, witness ? &*witness : nullptr};
  try {
    report.interrupted = !RunPhases(args, parts, stop, report, log);
    StopPipeline(processes, bus, scorer);
  } catch (const ProgramFailure& e) {
    processes.StopAll();
    report.failure = e.what();
    report.programs = processes.ends();
    WriteOutputs(report, settings.out, log);
    throw;
  }
  processes.StopAll();
  report.sensing = scorer.Finish(NowUtime());
  report.programs = processes.ends();
  if (report.rig) JudgeLogs(plan.log, *report.rig);
  WriteOutputs(report, settings.out, log);
  log << "wrote " << (settings.out / "report.json").string() << ", experiment.txt, "
      << "tip_paths.png; the programs' output is in " << plan.logs_dir.string() << "/\n";
  return report;
}

}  // namespace

// With three hosts, this process is the operator's: its bus, its census of
// the rig network and the programs it starts belong to a thread that has
// entered the operator host (each program then moves to its own host).
ExperimentReport RunClosedLoopExperiment(const ExperimentArgs& args, const std::atomic<bool>& stop,
                                         std::ostream& log) {
  if (args.hosts == nullptr) return RunExperimentHere(args, stop, log);
  ExperimentReport report;
  std::exception_ptr error;
  std::thread([&] {
    try {
      args.hosts->EnterFromThisThread(kOperatorHostName);
      report = RunExperimentHere(args, stop, log);
    } catch (...) {
      error = std::current_exception();
    }
  }).join();
  if (error) std::rethrow_exception(error);
  return report;
}

}  // namespace shapesense
