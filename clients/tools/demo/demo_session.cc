#include "clients/tools/demo/demo_session.h"

#include <chrono>
#include <fstream>
#include <string>
#include <thread>

#include "clients/tools/demo/live_demo.h"
#include "libs/camera/rig_yaml.h"
#include "runtime/file_io.h"
#include "runtime/process/listening_socket.h"

namespace shapesense {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

DemoSettings BaseDemoSettings(const fs::path& bin_dir, const fs::path& lcm_logger,
                              const fs::path& out, const Rig& rig, double rate_hz, uint32_t seed) {
  DemoSettings settings;
  settings.bin_dir = bin_dir.empty() ? ExecutableDir() : bin_dir;
  settings.lcm_logger = lcm_logger.empty() ? FindOnPath("lcm-logger") : lcm_logger;
  if (settings.lcm_logger.empty()) settings.lcm_logger = "/usr/bin/lcm-logger";  // named as missing
  settings.out = fs::absolute(out);
  for (const Camera& camera : rig.cameras) settings.camera_names.push_back(camera.name);
  settings.rate_hz = rate_hz;
  settings.seed = seed;
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
  throw ProgramFailure("", message);
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
bool StartAll(ProcessGroup& processes, const std::vector<ProgramSpec>& list, std::ostream& log) {
  if (list.empty()) return true;
  const size_t last = list.size() - 1;
  for (size_t i = 0; i < last; ++i) {
    log << "  starting " << list[i].name << std::endl;
    processes.Launch(list[i]);
  }
  for (size_t i = 0; i < last; ++i) {
    if (!processes.WaitUntilUp(list[i].name, kDemoStartTimeout)) return false;
  }
  log << "  starting " << list[last].name << std::endl;
  return processes.Start(list[last], kDemoStartTimeout);
}

// The capture service first; then the frame-sets in flight drain through
// (no new shape for a while) before the services and the logger stop.
void StopPipeline(ProcessGroup& processes, LcmBus& bus, const DemoScorer& scorer) {
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

int64_t FileBytes(const fs::path& path) {
  std::error_code error;
  const auto bytes = fs::file_size(path, error);
  return error ? 0 : static_cast<int64_t>(bytes);
}

void PrintMonitorUrl(int monitor_socket, std::ostream& log) {
  if (monitor_socket < 0) return;
  log << "monitor: http://" << ListeningAddress(monitor_socket)
      << "/ (open it in a browser on this machine; it lives while the pipeline runs)" << std::endl;
}

}  // namespace shapesense
