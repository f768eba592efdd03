// Latency of the live sensing pipeline (issue 3): the real shapesense-carving
// and shapesense-shape processes on LCM over loopback, fed by this bench
// playing three cameras of a synthetic rig the way the capture service
// publishes them (instant cameras: the trigger is stamped when the set is
// published, so trigger → shape is what the pipeline adds).
//
// Prints, at the first rate (100 Hz): latency trigger → shape received p50 /
// p90 / p99 / max, its breakdown by the stage times the shapes carry, frame-sets
// sent / measured / dropped, and whether p99 ≤ the target (5 ms); then steps the
// rate up until a step drops frame-sets and prints the highest rate without drops.
// A step is clean when every frame-set sent came back as a shape and neither
// service counted a drop or an error (their 1 Hz status). Asserts nothing:
// the figures depend on the machine and its load.
#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "runtime/lcm/channels.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/lcm/pipeline_stages.h"
#include "runtime/process/child_process.h"
#include "runtime/process/private_network.h"
#include "runtime/security/key_file.h"
#include "tests/bench/latency_bench_rig.h"
#include "tests/bench/latency_stats.h"
#include "tests/bench/pipeline_listener.h"
#include "tests/bench/process_probe.h"

namespace shapesense::bench {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// LCM's own default, host-only (ttl=0); inside the private namespace it stays there.
constexpr const char* kLcmUrl = "udpm://239.255.76.67:7667?ttl=0";
constexpr int kLcmPort = 7667;

struct BenchOptions {
  // Frame-set rates, Hz, in order: a detailed step at the first, then a
  // short step at each until one drops.
  std::vector<double> rates = {100, 150, 200, 300, 400, 600, 800};
  double first_seconds = 5.0;
  double step_seconds = 3.0;
  double target_p99_ms = 5.0;
  int width = 640;
  int height = 480;
  int frame_sets = 24;  // distinct sets rendered ahead, played in turn
  double voxel_size = 1.0;
  int recv_buf_size = 4194304;  // of every LCM receiver
  // Empty: the services' defaults (as config/*_service.yaml).
  std::string carving_config;
  std::string shape_config;
  int nice = 0;              // of the bench and the services (< 0 needs privileges)
  bool tune_malloc = false;  // the services keep freed memory (see ServiceEnvironment)
  bool details = false;      // the breakdown of every step, not only the first and the failing one
  // Message authentication (docs/security.md): "off", "on" (the services
  // and the listener hold a key: the shapes are signed and verified), or
  // "compare": the first step without, then with, and what it adds.
  std::string auth = "off";
};

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// ---- the services ------------------------------------------------------------

struct Counters {
  int64_t received = 0, published = 0, dropped = 0, rejected = 0, errors = 0;
  std::string last_error;
};

Counters CountersOf(const std::optional<service_status_t>& status) {
  if (!status) return {};
  return {status->received, status->published, status->dropped,
          status->rejected, status->errors,    status->last_error};
}

Counters Difference(const Counters& after, const Counters& before) {
  return {after.received - before.received,
          after.published - before.published,
          after.dropped - before.dropped,
          after.rejected - before.rejected,
          after.errors - before.errors,
          after.last_error != before.last_error ? after.last_error : ""};
}

struct ServiceSnapshot {
  Counters carving, shape;
};

ServiceSnapshot Snapshot(const PipelineListener& listener) {
  return {CountersOf(listener.Status("carving")), CountersOf(listener.Status("shape"))};
}

class TempFolder {
 public:
  TempFolder() {
    std::string pattern = (fs::temp_directory_path() / "shapesense-latency-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("cannot create a temp folder");
    path_ = pattern;
  }
  ~TempFolder() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// The backgrounds only for the carving service: it sends the shape service silhouettes.
std::vector<std::string> ServiceArgv(const fs::path& program, const std::string& config,
                                     const fs::path& folder, const std::string& url) {
  std::vector<std::string> argv = {
      program.string(), "--config", config, "--rig", (folder / "rig.yaml").string(),
      "--lcm-url",      url};
  if (program.filename() == "shapesense-carving") {
    argv.insert(argv.end(), {"--backgrounds", (folder / "background").string()});
  }
  return argv;
}

// The carving config: the user's, or the defaults with the bench's voxel size.
std::string CarvingConfig(const BenchOptions& options, const fs::path& folder) {
  if (!options.carving_config.empty()) return fs::absolute(options.carving_config).string();
  const fs::path path = folder / "carving_service.yaml";
  std::ofstream(path) << "carving:\n  voxel_size: " << options.voxel_size << "\n";
  return path.string();
}

std::string ShapeConfig(const BenchOptions& options, const fs::path& folder) {
  if (!options.shape_config.empty()) return fs::absolute(options.shape_config).string();
  const fs::path path = folder / "shape_service.yaml";
  std::ofstream(path) << "{}\n";
  return path.string();
}

struct Services {
  std::unique_ptr<ChildProcess> carving, shape;
};

// Large image buffers (900 KB at 640x480) come from mmap by default and go
// back to the kernel when freed, so every message costs page faults and
// zeroing; with these tunables glibc keeps them. An experiment for the
// services' mains (mallopt), which the bench can run without changing them.
void ServiceEnvironment(const BenchOptions& options) {
  if (!options.tune_malloc) return;
  setenv("GLIBC_TUNABLES",
         "glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=1073741824", 1);
}

Services StartServices(const BenchOptions& options, const fs::path& folder,
                       const std::string& url) {
  const fs::path bin = fs::read_symlink("/proc/self/exe").parent_path();
  for (const char* name : {"shapesense-carving", "shapesense-shape"}) {
    if (!fs::exists(bin / name)) {
      throw std::runtime_error((bin / name).string() + " not found: build it (ninja " + name + ")");
    }
  }
  ServiceEnvironment(options);
  Services services;
  services.carving = std::make_unique<ChildProcess>(
      ServiceArgv(bin / "shapesense-carving", CarvingConfig(options, folder), folder, url));
  services.shape = std::make_unique<ChildProcess>(
      ServiceArgv(bin / "shapesense-shape", ShapeConfig(options, folder), folder, url));
  return services;
}

void StopServices(Services& services) {
  if (services.shape) services.shape->Stop();
  if (services.carving) services.carving->Stop();
}

// ---- playing a rate ----------------------------------------------------------

struct StepResult {
  double rate_hz = 0.0;
  double achieved_hz = 0.0;  // as published (the bench may fall behind)
  int64_t first_seq = 0;
  int64_t sent = 0;
  int64_t images_sent = 0;
  int64_t publish_failures = 0;
  std::vector<double> publish_ms;  // trigger to the set's last image handed to LCM
  std::vector<ShapeSample> shapes;
  int64_t invalid_shapes = 0;
  Counters carving, shape;  // the step's share of the services' counters
  bool status_fresh = false;
  std::map<int, ProcessProbe> probe_before, probe_after;  // by pid
  double in_process_ms = 0.0;  // CPU of the same chain in one thread, per frame-set

  int64_t Missing() const { return sent - static_cast<int64_t>(shapes.size()); }
  bool PlayerKeptUp() const { return achieved_hz >= 0.97 * rate_hz && publish_failures == 0; }
  bool Clean() const {
    return Missing() == 0 && carving.dropped == 0 && shape.dropped == 0 && carving.errors == 0 &&
           shape.errors == 0;
  }
};

// Publishes at `rate_hz` for `ticks` ticks of a fixed schedule. A tick the
// bench reaches more than a period late is skipped rather than published in
// a burst (the achieved rate then falls short of the asked one).
void Play(FrameSetPlayer& player, double rate_hz, int64_t ticks, StepResult* result) {
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / rate_hz));
  const auto start = Clock::now();
  for (int64_t tick = 0; tick < ticks; ++tick) {
    const auto due = start + period * tick;
    std::this_thread::sleep_until(due);
    const auto now = Clock::now();
    if (now - due > period) continue;
    if (player.Publish(result->first_seq + result->sent) < 0) ++result->publish_failures;
    ++result->sent;
    result->publish_ms.push_back(Seconds(Clock::now() - now) * 1e3);
  }
  result->images_sent = result->sent * player.cameras();
  result->achieved_hz = rate_hz * static_cast<double>(result->sent) / static_cast<double>(ticks);
}

// Waits (bounded) for the shapes of the step, and takes the processes' CPU
// figures when they are in (the wait for statuses after it is the bench's,
// and would charge the services' idle time to the step's frame-sets); then
// waits for statuses published after the pipeline went quiet (a set that
// lost an image times out in the carving service's assembly after 200 ms,
// an unpaired cloud in the shape service after 500 ms: 1.5 s covers both).
void Drain(const PipelineListener& listener, StepResult* result) {
  const auto end = Clock::now() + milliseconds(1500);
  const int64_t last = result->first_seq + result->sent;
  while (Clock::now() < end &&
         listener.CountShapes(result->first_seq, last) < static_cast<size_t>(result->sent)) {
    std::this_thread::sleep_for(milliseconds(1));
  }
  result->probe_after = ProbeProcesses(kLcmPort);
  result->status_fresh = WaitForStatuses(listener, NowUtime(), milliseconds(3000));
  result->shapes = listener.Shapes(result->first_seq, last);
  for (const ShapeSample& shape : result->shapes) result->invalid_shapes += shape.valid ? 0 : 1;
}

StepResult RunStep(FrameSetPlayer& player, const PipelineListener& listener, double in_process_ms,
                   double rate_hz, double seconds, int64_t* next_seq) {
  StepResult result;
  result.rate_hz = rate_hz;
  result.in_process_ms = in_process_ms;
  result.first_seq = *next_seq;
  const ServiceSnapshot before = Snapshot(listener);
  result.probe_before = ProbeProcesses(kLcmPort);
  Play(player, rate_hz, std::max<int64_t>(2, std::llround(rate_hz * seconds)), &result);
  *next_seq += result.sent;
  Drain(listener, &result);
  const ServiceSnapshot after = Snapshot(listener);
  result.carving = Difference(after.carving, before.carving);
  result.shape = Difference(after.shape, before.shape);
  return result;
}

// ---- printing ------------------------------------------------------------------

std::vector<double> TotalsMs(const std::vector<ShapeSample>& shapes) {
  std::vector<double> totals;
  totals.reserve(shapes.size());
  for (const ShapeSample& s : shapes) {
    totals.push_back(static_cast<double>(s.receive_utime - s.trigger_utime) * 1e-3);
  }
  return totals;
}

void PrintCounters(const char* service, const Counters& c, const char* received_what) {
  std::printf(
      "    %-8s %6lld %s received, %6lld published, %lld dropped, %lld rejected, %lld "
      "errors%s%s\n",
      service, static_cast<long long>(c.received), received_what,
      static_cast<long long>(c.published), static_cast<long long>(c.dropped),
      static_cast<long long>(c.rejected), static_cast<long long>(c.errors),
      c.last_error.empty() ? "" : "; last: ", c.last_error.c_str());
}

// CPU per frame-set of the carving and shape services together over the step.
double ServicesCpuMs(const StepResult& r) {
  double ms = 0.0;
  for (const auto& [pid, after] : r.probe_after) {
    const auto before = r.probe_before.find(pid);
    if (before == r.probe_before.end() || after.name.rfind("shapesense-", 0) != 0) continue;
    ms += 1e3 * (after.cpu_seconds - before->second.cpu_seconds) /
          static_cast<double>(std::max<int64_t>(r.sent, 1));
  }
  return ms;
}

// CPU per frame-set and receive-socket drops of each process over the step.
void PrintProcesses(const StepResult& r) {
  std::string cpu, drops;
  double total_ms = 0.0;
  for (const auto& [pid, after] : r.probe_after) {
    const auto before = r.probe_before.find(pid);
    if (before == r.probe_before.end()) continue;
    const double ms = 1e3 * (after.cpu_seconds - before->second.cpu_seconds) /
                      static_cast<double>(std::max<int64_t>(r.sent, 1));
    total_ms += ms;
    char text[160];
    std::snprintf(text, sizeof(text), "%s%s %.2f", cpu.empty() ? "" : ", ", after.name.c_str(), ms);
    cpu += text;
    std::snprintf(text, sizeof(text), "%s%s %lld", drops.empty() ? "" : ", ", after.name.c_str(),
                  static_cast<long long>(after.udp_drops - before->second.udp_drops));
    drops += text;
  }
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  std::printf("         CPU ms per frame-set: %s; all %.2f (%u cores: at most %.0f sets/s)\n",
              cpu.c_str(), total_ms, cores, total_ms > 0 ? cores * 1e3 / total_ms : 0.0);
  const double services_ms = ServicesCpuMs(r);
  if (r.in_process_ms > 0 && services_ms > 0) {
    std::printf(
        "         the services (carving + shape) %.2f ms: %.2f x the chain in one thread (%.2f)\n",
        services_ms, services_ms / r.in_process_ms, r.in_process_ms);
  }
  std::printf(
      "         datagrams dropped at the receive sockets (buffer full): %s; images lost "
      "before the carving service's handler: %lld\n",
      drops.c_str(), static_cast<long long>(r.images_sent - r.carving.received));
}

void PrintDetailedStep(const StepResult& r, double target_ms) {
  std::printf("\nAt %.0f Hz for %lld frame-sets (published at %.1f Hz):\n", r.rate_hz,
              static_cast<long long>(r.sent), r.achieved_hz);
  std::printf(
      "  frame-sets: %lld sent, %zu measured (shapes received, %lld not valid), %lld "
      "dropped\n",
      static_cast<long long>(r.sent), r.shapes.size(), static_cast<long long>(r.invalid_shapes),
      static_cast<long long>(r.Missing()));
  std::printf("  services' counters over the step%s:\n",
              r.status_fresh ? "" : " (no fresh status: may miss the end)");
  PrintCounters("carving", r.carving, "images");
  PrintCounters("shape", r.shape, "clouds");
  const Percentiles publish = Summarize(r.publish_ms);
  std::printf("  publishing a frame-set (the bench, %lld images): p50 %.3f  p99 %.3f ms\n",
              static_cast<long long>(r.images_sent / std::max<int64_t>(r.sent, 1)), publish.p50,
              publish.p99);
  const Percentiles total = Summarize(TotalsMs(r.shapes));
  std::printf("  latency trigger -> shape received: p50 %.3f  p90 %.3f  p99 %.3f  max %.3f ms\n",
              total.p50, total.p90, total.p99, total.max);
  std::printf("  breakdown by the shapes' stage times (segments add up to the total):\n");
  PrintBreakdown(BreakDown(r.shapes));
  PrintProcesses(r);
  const bool met = total.count > 0 && total.p99 <= target_ms && r.Clean();
  std::printf(
      "  target p99 <= %.1f ms at %.0f Hz without drops: %s (p99 %.3f ms, %lld frame-sets "
      "dropped)\n",
      target_ms, r.rate_hz, met ? "MET" : "NOT MET", total.p99,
      static_cast<long long>(r.Missing()));
}

void PrintStepHeader() {
  std::printf("\n  %6s %8s %6s %6s %7s %13s %13s %8s %8s %8s  %s\n", "Hz", "sent at", "sent",
              "shapes", "missing", "carving d/e", "shape d/e", "p50 ms", "p99 ms", "max ms",
              "verdict");
}

void PrintStepLine(const StepResult& r, bool with_processes) {
  const Percentiles p = Summarize(TotalsMs(r.shapes));
  const char* verdict = !r.PlayerKeptUp() ? "bench could not publish at this rate"
                        : r.Clean()       ? "no drops"
                                          : "DROPS";
  std::printf("  %6.0f %8.1f %6lld %6zu %7lld %6lld/%-6lld %6lld/%-6lld %8.3f %8.3f %8.3f  %s\n",
              r.rate_hz, r.achieved_hz, static_cast<long long>(r.sent), r.shapes.size(),
              static_cast<long long>(r.Missing()), static_cast<long long>(r.carving.dropped),
              static_cast<long long>(r.carving.errors), static_cast<long long>(r.shape.dropped),
              static_cast<long long>(r.shape.errors), p.p50, p.p99, p.max, verdict);
  if (!r.Clean()) {
    const std::string& why =
        !r.carving.last_error.empty() ? r.carving.last_error : r.shape.last_error;
    if (!why.empty()) std::printf("         last note: %s\n", why.c_str());
  }
  if (with_processes) PrintProcesses(r);
}

// ---- the run -------------------------------------------------------------------

BenchRig Prepare(const BenchOptions& options) {
  const auto start = Clock::now();
  BenchRigOptions rig_options;
  rig_options.width = options.width;
  rig_options.height = options.height;
  rig_options.frame_sets = options.frame_sets;
  rig_options.threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  BenchRig rig = MakeBenchRig(rig_options);
  std::printf("Rendered %d frame-sets of %zu cameras at %dx%d in %.1f s (ahead of timing)\n",
              options.frame_sets, rig.rig.cameras.size(), options.width, options.height,
              Seconds(Clock::now() - start));
  return rig;
}

double ThreadCpuSeconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

// The yardstick of the services' cost: the same chain on the same frame-sets
// in one thread (CarvingStage, then ShapeStage on its compact silhouettes,
// default options and the bench's voxel size), CPU ms per frame-set over
// three passes after a warm-up one.
double InProcessCpuMs(const BenchRig& rig, const BenchOptions& options) {
  CarvingOptions carving;
  carving.voxel_size = options.voxel_size;
  const CarvingStage carving_stage(rig.rig, rig.backgrounds, SilhouetteOptions{}, carving);
  const ShapeStage shape_stage(rig.rig, ShapeOptions{});
  std::vector<FrameSet> sets(rig.frame_sets.size());
  for (size_t i = 0; i < sets.size(); ++i) {
    sets[i].trigger_seq = static_cast<int64_t>(i);
    sets[i].images = rig.frame_sets[i];
  }
  CarvingOutput carved;
  ShapeOutput shaped;
  const auto pass = [&] {
    for (const FrameSet& set : sets) {
      if (carving_stage.Process(set, &carved).empty()) {
        shape_stage.Process(carved.message, &carved.compact, &shaped);
      }
    }
  };
  pass();
  constexpr int kPasses = 3;
  const double start = ThreadCpuSeconds();
  for (int i = 0; i < kPasses; ++i) pass();
  const double ms = 1e3 * (ThreadCpuSeconds() - start) / static_cast<double>(kPasses * sets.size());
  std::printf("The same chain in one thread on these frame-sets: %.2f ms CPU per frame-set%s\n", ms,
              options.carving_config.empty() ? "" : " (default carving options)");
  return ms;
}

// Ramps the rate from rates[1] until a step is not clean; returns the highest clean rate.
double Ramp(const BenchOptions& options, FrameSetPlayer& player, const PipelineListener& listener,
            const StepResult& first, int64_t* next_seq) {
  PrintStepHeader();
  PrintStepLine(first, false);  // detailed above
  if (!first.Clean() || !first.PlayerKeptUp()) return 0.0;
  double sustained = first.rate_hz;
  for (size_t i = 1; i < options.rates.size(); ++i) {
    const StepResult step = RunStep(player, listener, first.in_process_ms, options.rates[i],
                                    options.step_seconds, next_seq);
    PrintStepLine(step, true);
    const bool stop = !step.Clean() || !step.PlayerKeptUp();
    if (options.details || stop) {
      std::printf("    breakdown at %.0f Hz:\n", step.rate_hz);
      PrintBreakdown(BreakDown(step.shapes));
    }
    std::fflush(stdout);
    if (stop) break;
    sustained = step.rate_hz;
  }
  return sustained;
}

// The 1-minute load average and the number of cores: the figures depend on both.
std::string MachineLoad() {
  std::ifstream file("/proc/loadavg");
  std::string load = "?";
  file >> load;
  return "load average " + load + " on " + std::to_string(std::thread::hardware_concurrency()) +
         " cores";
}

void PrintSummary(const BenchOptions& options, const StepResult& first, double sustained) {
  const Percentiles p = Summarize(TotalsMs(first.shapes));
  std::printf(
      "\nSummary (%s): at %.0f Hz trigger -> shape p50 %.3f ms, p99 %.3f ms (target p99 <= %.1f "
      "ms: %s); highest sustained frame-set rate without drops: ",
      MachineLoad().c_str(), first.rate_hz, p.p50, p.p99, options.target_p99_ms,
      p.count > 0 && p.p99 <= options.target_p99_ms && first.Clean() ? "met" : "NOT met");
  if (sustained > 0) {
    std::printf("%.0f Hz%s\n", sustained,
                sustained == options.rates.back() ? " (the highest rate tried)" : "");
  } else {
    std::printf("none (below %.0f Hz)\n", options.rates.front());
  }
}

// Prints the conditions of the run; applies --nice (before any thread starts:
// threads and children inherit it). Returns the receivers' LCM URL.
std::string PrintSetup(const BenchOptions& options, const std::string& network_error) {
  std::printf("Machine: %s\n", MachineLoad().c_str());
  if (network_error.empty()) {
    std::printf("Network: a private network namespace (loopback only)\n");
  } else {
    std::printf("Network: no private namespace (%s); using LCM's host-only default on loopback\n",
                network_error.c_str());
  }
  if (options.nice != 0) {
    const bool set = setpriority(PRIO_PROCESS, 0, options.nice) == 0;
    std::printf("Priority: nice %d%s\n", options.nice, set ? "" : " refused (no privilege)");
  }
  if (options.tune_malloc) std::printf("Services: glibc malloc tuned (--tune-malloc)\n");
  std::string receive_url =
      std::string(kLcmUrl) + "&recv_buf_size=" + std::to_string(options.recv_buf_size);
  std::printf("LCM: %s (publisher: %s)\n", receive_url.c_str(), kLcmUrl);
  return receive_url;
}

// Gives the services started from now on, and the listener made after, the
// rig key in `folder` (SHAPESENSE_KEY_FILES), or none.
void UseKey(bool on, const fs::path& folder) {
  if (!on) {
    unsetenv("SHAPESENSE_KEY_FILES");
    return;
  }
  const fs::path key = folder / "rig.key";
  if (!fs::exists(key)) WriteKeyFile(key, NewAuthKey(1));
  setenv("SHAPESENSE_KEY_FILES", key.c_str(), 1);
}

// The services and the listener, up and reporting; the first step measured
// (after a warm-up), then, unless only the first is wanted, the ramp.
struct Session {
  StepResult first;
  double sustained = 0.0;
  bool ok = false;
};

Session Measure(const BenchOptions& options, BenchRig& rig, double in_process_ms,
                const fs::path& folder, const std::string& receive_url, bool ramp) {
  Session session;
  PipelineListener listener(receive_url);
  Services services = StartServices(options, folder, receive_url);
  std::printf(
      "Waiting for shapesense-carving (builds its carving table) and shapesense-shape...\n");
  std::fflush(stdout);
  if (!WaitForStatuses(listener, 0, milliseconds(120000))) {
    std::printf("The services did not report within 120 s (see their messages above)\n");
    return session;
  }
  FrameSetPlayer player(rig, kLcmUrl);
  int64_t next_seq = 0;
  // warm-up, not counted
  RunStep(player, listener, in_process_ms, options.rates.front(), 1.0, &next_seq);
  session.first = RunStep(player, listener, in_process_ms, options.rates.front(),
                          options.first_seconds, &next_seq);
  PrintDetailedStep(session.first, options.target_p99_ms);
  if (ramp) {
    std::printf("\nStepping the rate up (%.1f s a step; d/e: the service's drops / errors):",
                options.step_seconds);
    session.sustained = Ramp(options, player, listener, session.first, &next_seq);
  }
  std::printf("\nStopping the services:\n");
  std::fflush(stdout);
  StopServices(services);
  session.ok = true;
  return session;
}

// The first step without and with authentication, in the order off, on,
// on, off, so that a drift of the machine falls on both alike; the samples
// of each pooled. The shape service signs each shape before it leaves (in
// the last segment, "shape -> bench socket"); the bench verifies it after.
int CompareAuth(const BenchOptions& options, BenchRig& rig, double in_process_ms,
                const fs::path& folder, const std::string& receive_url) {
  std::map<bool, std::vector<double>> totals, last_segment;
  for (const bool on : {false, true, true, false}) {
    std::printf("\n== authentication %s ==\n", on ? "on (the shapes signed and verified)" : "off");
    UseKey(on, folder);
    const Session session = Measure(options, rig, in_process_ms, folder, receive_url, false);
    if (!session.ok) return 1;
    const LatencyBreakdown breakdown = BreakDown(session.first.shapes);
    totals[on].insert(totals[on].end(), breakdown.total.begin(), breakdown.total.end());
    last_segment[on].insert(last_segment[on].end(), breakdown.segments.back().begin(),
                            breakdown.segments.back().end());
  }
  std::printf("\nAuthentication at %.0f Hz (%s), two sessions each, pooled:\n",
              options.rates.front(), MachineLoad().c_str());
  for (const auto& [name, samples] : {std::pair{"trigger -> shape", &totals},
                                      std::pair{"shape -> bench socket", &last_segment}}) {
    const Percentiles off = Summarize((*samples)[false]);
    const Percentiles on = Summarize((*samples)[true]);
    std::printf(
        "  %-22s off p50 %.3f p99 %.3f ms; on p50 %.3f p99 %.3f ms; added p50 %+.3f p99 "
        "%+.3f ms\n",
        name, off.p50, off.p99, on.p50, on.p99, on.p50 - off.p50, on.p99 - off.p99);
  }
  return 0;
}

int Run(const BenchOptions& options, const std::string& network_error) {
  if (options.rates.empty()) throw std::invalid_argument("--rates: expected at least one rate");
  const std::string receive_url = PrintSetup(options, network_error);
  BenchRig rig = Prepare(options);
  const double in_process_ms = InProcessCpuMs(rig, options);
  const TempFolder folder;
  WriteBenchRig(rig, folder.path());
  if (options.auth == "compare") {
    return CompareAuth(options, rig, in_process_ms, folder.path(), receive_url);
  }
  UseKey(options.auth == "on", folder.path());
  const Session session = Measure(options, rig, in_process_ms, folder.path(), receive_url, true);
  if (!session.ok) return 1;
  PrintSummary(options, session.first, session.sustained);
  return 0;
}

int ParseOptions(int argc, char** argv, BenchOptions* options) {
  CLI::App app{
      "pipeline_latency_bench: latency trigger -> shape of the live pipeline "
      "(shapesense-carving and shapesense-shape over LCM on loopback) and its highest "
      "frame-set rate without drops"};
  app.add_option("--rates", options->rates, "frame-set rates to step through, Hz (first: detailed)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  app.add_option("--first-seconds", options->first_seconds,
                 "duration of the first, detailed step, s")
      ->check(CLI::Range(0.5, 60.0));
  app.add_option("--step-seconds", options->step_seconds, "duration of each further step, s")
      ->check(CLI::Range(0.5, 60.0));
  app.add_option("--width", options->width, "image width, px")->check(CLI::Range(64, 4096));
  app.add_option("--height", options->height, "image height, px")->check(CLI::Range(48, 4096));
  app.add_option("--frame-sets", options->frame_sets, "distinct frame-sets rendered ahead")
      ->check(CLI::Range(1, 500));
  app.add_option("--voxel-size", options->voxel_size, "carving voxel size, mm (default config: 1)")
      ->check(CLI::Range(0.5, 8.0));
  app.add_option("--target-ms", options->target_p99_ms, "target p99 trigger -> shape, ms");
  app.add_option("--recv-buf-size", options->recv_buf_size,
                 "LCM recv_buf_size of the receivers, bytes (net.core.rmem_max caps it)")
      ->check(CLI::Range(65536, 1 << 30));
  app.add_option("--carving-config", options->carving_config,
                 "config of shapesense-carving (default: its defaults, --voxel-size)")
      ->check(CLI::ExistingFile);
  app.add_option("--shape-config", options->shape_config, "config of shapesense-shape")
      ->check(CLI::ExistingFile);
  app.add_option("--nice", options->nice,
                 "nice value of the bench and the services (negative: needs privileges)")
      ->check(CLI::Range(-20, 19));
  app.add_option("--auth", options->auth,
                 "message authentication: off, on, or compare (the first step without, then with)")
      ->check(CLI::IsMember({"off", "on", "compare"}));
  app.add_flag("--tune-malloc", options->tune_malloc,
               "run the services with glibc's malloc keeping freed memory (GLIBC_TUNABLES)");
  app.add_flag(
      "--details", options->details,
      "print the latency breakdown of every step (default: the first and the failing one)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  return -1;
}

}  // namespace
}  // namespace shapesense::bench

int main(int argc, char** argv) {
  // First, while single-threaded: everything after runs in the private namespace.
  const std::string network_error = shapesense::EnterPrivateNetwork(0);
  shapesense::bench::BenchOptions options;
  if (const int exit_code = shapesense::bench::ParseOptions(argc, argv, &options); exit_code >= 0)
    return exit_code;
  try {
    return shapesense::bench::Run(options, network_error);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pipeline_latency_bench: %s\n", e.what());
    return 1;
  }
}
