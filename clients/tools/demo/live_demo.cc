#include "clients/tools/demo/live_demo.h"

#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

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
constexpr auto kStartTimeout = std::chrono::seconds(120);  // a sanitizer build's carving table

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

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
  DemoSettings settings;
  settings.bin_dir = args.bin_dir.empty() ? ExecutableDir() : args.bin_dir;
  settings.lcm_logger = args.lcm_logger.empty() ? FindOnPath("lcm-logger") : args.lcm_logger;
  if (settings.lcm_logger.empty()) settings.lcm_logger = "/usr/bin/lcm-logger";  // named as missing
  settings.out = fs::absolute(args.out);
  settings.cameras = args.cameras;
  for (const Camera& camera : rig.cameras) settings.camera_names.push_back(camera.name);
  settings.rate_hz = args.rate_hz;
  settings.duration_s = args.duration_s;
  settings.seed = args.seed;
  return settings;
}

// A fresh output folder with the rig file (and the simulated cameras' config).
void PrepareOutput(const DemoPlan& plan, const Rig& rig) {
  for (const fs::path& old : {plan.log, plan.report, plan.replay_shapes}) fs::remove(old);
  fs::remove_all(plan.backgrounds);
  fs::create_directories(plan.backgrounds);
  WriteFileAtomically(plan.rig, FormatRigYaml(rig));
  if (!plan.capture_config.empty()) {
    WriteFileAtomically(plan.capture_config, plan.capture_config_text);
  }
}

// Receivers of images ask LCM for 4 MB socket buffers; the kernel grants at
// most net.core.rmem_max, and less loses images of whole frame-sets.
void WarnIfSocketBuffersAreSmall(std::ostream& log) {
  constexpr long kWanted = 4194304;
  long limit = 0;
  std::ifstream("/proc/sys/net/core/rmem_max") >> limit;
  if (limit <= 0 || limit >= kWanted) return;
  log << "demo: the kernel caps socket buffers at " << limit
      << " bytes (net.core.rmem_max), below the " << kWanted
      << " that receivers of images ask for: expect lost frame-sets.\n"
         "      As root: sysctl -w net.core.rmem_max="
      << kWanted << std::endl;
}

void ThrowIfMissing(const DemoPlan& plan) {
  const std::vector<std::string> missing = MissingPrograms(plan);
  if (missing.empty()) return;
  std::string message = "the demo cannot run:";
  for (const std::string& line : missing) message += "\n  " + line;
  throw DemoFailure("", message);
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

// Handles the bus for about `ms` (LCM's wait ends at each message).
void Pump(LcmBus& bus, int ms) {
  const auto end = Clock::now() + std::chrono::milliseconds(ms);
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - Clock::now());
    if (left.count() <= 0) return;
    if (bus.Handle(static_cast<int>(left.count())) < 0) std::this_thread::sleep_for(left);
  }
}

// Starts all but the last side by side, and the last (the one that needs
// the others: the capture service) once they are all up. False when stopped
// meanwhile.
bool StartAll(DemoProcesses& processes, const std::vector<DemoProcess>& list, std::ostream& log) {
  if (list.empty()) return true;
  const size_t last = list.size() - 1;
  for (size_t i = 0; i < last; ++i) {
    log << "  starting " << list[i].name << std::endl;
    processes.Launch(list[i]);
  }
  for (size_t i = 0; i < last; ++i) {
    if (!processes.WaitUntilUp(list[i].name, kStartTimeout)) return false;
  }
  log << "  starting " << list[last].name << std::endl;
  return processes.Start(list[last], kStartTimeout);
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
double Measure(const LiveDemoArgs& args, DemoProcesses& processes, LcmBus& bus,
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

// The capture service first; then the frame-sets in flight drain through
// (no new shape for a while) before the services and the logger stop.
void StopPipeline(DemoProcesses& processes, LcmBus& bus, const DemoScorer& scorer) {
  processes.Stop("capture");
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  auto quiet_since = Clock::now();
  int shapes = scorer.shapes();
  while (Clock::now() < deadline && SecondsSince(quiet_since) < 0.7) {
    Pump(bus, 50);
    processes.ReadOutput();
    if (scorer.shapes() != shapes) {
      shapes = scorer.shapes();
      quiet_since = Clock::now();
    }
  }
  processes.StopAll();
}

ReplayCheck CheckReplay(const DemoPlan& plan, const DemoScorer& scorer, std::ostream& log) {
  ReplayArgs args;
  args.log = plan.log;
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

int64_t FileBytes(const fs::path& path) {
  std::error_code error;
  const auto bytes = fs::file_size(path, error);
  return error ? 0 : static_cast<int64_t>(bytes);
}

void FinishReport(LiveDemoReport& report, const DemoProcesses& processes, const DemoPlan& plan) {
  report.programs = processes.ends();
  report.log_bytes = FileBytes(plan.log);
  WriteFileAtomically(plan.report, LiveReportToJson(report).dump(2) + "\n");
}

// Both phases and the run; false when stopped before the end.
bool RunPhases(const LiveDemoArgs& args, const DemoPlan& plan, DemoProcesses& processes,
               LcmBus& bus, const DemoScorer& scorer, const std::atomic<bool>& stop,
               LiveDemoReport& report, std::ostream& log) {
  log << "backgrounds: the rig showing its backdrop alone, " << plan.backgrounds.string()
      << std::endl;
  if (!StartAll(processes, plan.background, log)) return false;
  processes.StopAll();
  log << "live pipeline, logged to " << plan.log.string() << std::endl;
  if (!StartAll(processes, plan.pipeline, log)) return false;
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
  const DemoSettings settings = MakeSettings(args, rig);
  const DemoPlan plan = MakeDemoPlan(settings);
  ThrowIfMissing(plan);
  WarnIfSocketBuffersAreSmall(log);
  PrepareOutput(plan, rig);
  LcmBus bus(settings.lcm_url);
  DemoScorer scorer;
  Subscribe(bus, scorer);
  DemoProcesses processes(plan.logs_dir, stop,
                          {[&bus](int ms) { Pump(bus, ms); },
                           [&scorer](const std::string& s) { return scorer.StatusSeen(s); }});
  LiveDemoReport report = StartReport(args, settings, plan);
  try {
    report.interrupted = !RunPhases(args, plan, processes, bus, scorer, stop, report, log);
  } catch (const DemoFailure& e) {
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
