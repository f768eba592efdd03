#include "clients/tools/demo/live_demo.h"
#include "clients/tools/demo/demo_auth.h"

#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include "clients/tools/demo/demo_session.h"
#include "clients/tools/replay/replay_command.h"
#include "libs/camera/rig_yaml.h"
#include "libs/core/error.h"
#include "libs/sim/scene_generators.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/lcm_bus.h"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;

void CheckArgs(const LiveDemoArgs& args) {
  if (!(args.duration_s > 0.0 && args.duration_s <= 3600.0)) {
    throw InputError("--duration: expected seconds in (0, 3600], got " +
                     std::to_string(args.duration_s));
  }
  if (!(args.rate_hz >= 1.0 && args.rate_hz <= 300.0)) {
    throw InputError("--rate: expected Hz in [1, 300], got " + std::to_string(args.rate_hz));
  }
}

DemoSettings MakeSettings(const LiveDemoArgs& args, const Rig& rig) {
  DemoSettings settings =
      BaseDemoSettings(args.bin_dir, args.lcm_logger, args.out, rig, args.rate_hz, args.seed);
  settings.cameras = args.cameras;
  settings.duration_s = args.duration_s;
  settings.monitor_socket = args.monitor_socket;
  return settings;
}

// What this process hears of the run: the truth, the shapes and every service's status.
void Subscribe(LcmBus& bus, DemoScorer& scorer) {
  bus.Subscribe<shape_t>(channels::kShape,
                         [&scorer](const shape_t& shape, const std::string&, int64_t utime) {
                           scorer.AddShape(shape, utime);
                         });
  bus.Subscribe<shape_t>(channels::kTruth, [&scorer](const shape_t& truth, const std::string&,
                                                     int64_t) { scorer.AddTruth(truth); });
  bus.Subscribe<service_status_t>(channels::kStatusPattern,
                                  [&scorer](const service_status_t& status, const std::string&,
                                            int64_t) { scorer.AddStatus(status); });
}

class ProgressPrinter {
 public:
  ProgressPrinter(DemoProgress mode, std::ostream& log)
      : mode_(mode), log_(log), period_s_(mode == DemoProgress::kTerminal ? 0.5 : 5.0) {}
  ~ProgressPrinter() {
    if (drawn_) log_ << std::endl;
  }
  void Update(const DemoScorer& scorer, double elapsed_s, double duration_s) {
    if (mode_ == DemoProgress::kOff || elapsed_s < next_s_) return;
    next_s_ = elapsed_s + period_s_;
    const std::string line = ProgressLine(scorer.Finish(NowUtime()).live, elapsed_s, duration_s);
    if (mode_ == DemoProgress::kTerminal) {
      log_ << "\r  " << line << "\033[K" << std::flush;
      drawn_ = true;
    } else {
      log_ << "  " << line << std::endl;
    }
  }

 private:
  DemoProgress mode_;
  std::ostream& log_;
  double period_s_;
  double next_s_ = period_s_;
  bool drawn_ = false;
};

// The measured run: until the duration has passed or `stop`; returns its length, s.
double Measure(const LiveDemoArgs& args, ProcessGroup& processes, LcmBus& bus,
               const DemoScorer& scorer, const std::atomic<bool>& stop, std::ostream& log) {
  const auto start = Clock::now();
  ProgressPrinter progress(args.progress, log);
  while (!stop && SecondsSince(start) < args.duration_s) {
    Pump(bus, 50);
    processes.CheckRunning();
    progress.Update(scorer, SecondsSince(start), args.duration_s);
  }
  return SecondsSince(start);
}

ReplayCheck CheckReplay(const DemoPlan& plan, const DemoScorer& scorer, std::ostream& log) {
  ReplayArgs args;
  args.logs = plan.image_logs;
  args.out = plan.replay_shapes;
  args.rig = plan.rig;
  args.backgrounds = plan.backgrounds;
  args.progress = false;
  std::map<int64_t, shape_t> replayed;
  try {
    RunReplay(args, log,
              [&replayed](const shape_t& shape) { replayed[shape.trigger_seq] = shape; });
  } catch (const std::exception& e) {
    ReplayCheck failed;
    failed.error = e.what();
    return failed;
  }
  return CompareReplay(scorer.shapes_by_seq(), replayed);
}

LiveDemoReport StartReport(const LiveDemoArgs& args, const DemoSettings& settings,
                           const DemoPlan& plan) {
  LiveDemoReport report;
  report.network = args.network;
  report.cameras = CameraSourceName(args.cameras);
  report.lcm_url = settings.lcm_url;
  report.rate_hz = args.rate_hz;
  report.duration_s = args.duration_s;
  report.log = plan.log;
  return report;
}

void FinishReport(LiveDemoReport& report, const ProcessGroup& processes, const DemoPlan& plan) {
  report.programs = processes.ends();
  report.log_bytes = FileBytes(plan.log);
  WriteFileAtomically(plan.report, LiveReportToJson(report).dump(2) + "\n");
}

// Both phases and the run; false when stopped before the end.
bool RunPhases(const LiveDemoArgs& args, const DemoPlan& plan, ProcessGroup& processes, LcmBus& bus,
               const DemoScorer& scorer, const std::atomic<bool>& stop, LiveDemoReport& report,
               std::ostream& log) {
  log << "backgrounds: the rig showing its backdrop alone, " << plan.backgrounds.string()
      << std::endl;
  if (!StartAll(processes, plan.background, log)) return false;
  processes.StopAll();
  log << "live pipeline, logged to " << plan.log.string() << std::endl;
  if (!StartAll(processes, plan.pipeline, log)) return false;
  PrintMonitorUrl(args.monitor_socket, log);
  const int64_t start_utime = NowUtime();
  log << "measuring for " << args.duration_s << " s (Ctrl-C stops early)" << std::endl;
  report.measured_s = Measure(args, processes, bus, scorer, stop, log);
  const int64_t end_utime = start_utime + static_cast<int64_t>(report.measured_s * 1e6);
  StopPipeline(processes, bus, scorer);
  report.score = scorer.Finish(end_utime);
  return !stop;
}

}  // namespace

fs::path ExecutableDir() {
  std::error_code error;
  const fs::path self = fs::read_symlink("/proc/self/exe", error);
  return error ? fs::current_path() : self.parent_path();
}

LiveDemoReport RunLiveDemo(const LiveDemoArgs& args, const std::atomic<bool>& stop,
                           std::ostream& log) {
  CheckArgs(args);
  SyntheticRigOptions rig_options;
  rig_options.seed = args.seed;
  const Rig rig = MakeSyntheticRig(rig_options);
  DemoSettings settings = MakeSettings(args, rig);
  settings.auth = PrepareDemoAuth(args.auth, settings.out / "setup", log);
  const DemoPlan plan = MakeDemoPlan(settings);
  ThrowIfMissing(plan);
  WarnIfSocketBuffersAreSmall(log);
  PrepareOutput(plan, rig);
  LcmBusOptions bus_options = LcmBusOptions::FromEnvironment(settings.lcm_url);
  bus_options.auth = settings.auth;
  LcmBus bus(bus_options);
  DemoScorer scorer;
  Subscribe(bus, scorer);
  ProcessGroup processes(plan.logs_dir, stop,
                         {[&bus](int ms) { Pump(bus, ms); },
                          [&scorer](const std::string& s) { return scorer.StatusSeen(s); }});
  LiveDemoReport report = StartReport(args, settings, plan);
  try {
    report.interrupted = !RunPhases(args, plan, processes, bus, scorer, stop, report, log);
  } catch (const ProgramFailure& e) {
    processes.StopAll();
    report.failure = e.what();
    FinishReport(report, processes, plan);
    throw;
  }
  processes.StopAll();
  report.log_bytes = FileBytes(plan.log);
  if (report.measured_s > 0.0) PrintLiveSummary(report, log);
  if (args.replay && !report.interrupted) report.replay = CheckReplay(plan, scorer, log);
  if (report.interrupted) report.replay.error = "interrupted";
  PrintReplayCheck(report.replay, log);
  FinishReport(report, processes, plan);
  log << "wrote " << plan.report.string() << "; the programs' output is in "
      << plan.logs_dir.string() << "/\n";
  return report;
}

}  // namespace shapesense
