#pragma once

// What the live demo and the closed-loop experiment share while their
// programs run: the output folder, the checks before anything starts,
// pumping this process's LCM bus, starting and stopping the pipeline.
#include <cstdint>
#include <filesystem>
#include <ostream>
#include <vector>

#include "clients/tools/demo/demo_plan.h"
#include "clients/tools/demo/demo_scorer.h"
#include "libs/camera/camera.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/process/process_group.h"

namespace shapesense {

// How long a program may take to come up (a sanitizer build's carving table).
inline constexpr auto kDemoStartTimeout = std::chrono::seconds(120);

// Settings for `rig`'s cameras over GigE, the programs in `bin_dir` (empty:
// beside this executable) and lcm-logger at `lcm_logger` (empty: on $PATH),
// writing to `out`; the rest are DemoSettings' defaults.
DemoSettings BaseDemoSettings(const std::filesystem::path& bin_dir,
                              const std::filesystem::path& lcm_logger,
                              const std::filesystem::path& out, const Rig& rig, double rate_hz,
                              uint32_t seed);

// A fresh output folder with the rig file (and the simulated cameras' config).
void PrepareOutput(const DemoPlan& plan, const Rig& rig);
// Says so when the kernel caps socket buffers below what image receivers ask.
void WarnIfSocketBuffersAreSmall(std::ostream& log);
// Throws ProgramFailure listing every program of `plan` that is missing.
void ThrowIfMissing(const DemoPlan& plan);
// Handles the bus for about `ms` (LCM's wait ends at each message).
void Pump(LcmBus& bus, int ms);
// Starts all but the last side by side, and the last (the one that needs
// the others: the capture service) once they are all up. False when stopped
// meanwhile.
bool StartAll(ProcessGroup& processes, const std::vector<ProgramSpec>& list, std::ostream& log);
// Stops the capture service first; then the frame-sets in flight drain
// through (no new shape for a while) before the rest stop.
void StopPipeline(ProcessGroup& processes, LcmBus& bus, const DemoScorer& scorer);
// Seconds on the steady clock since `start`.
double SecondsSince(std::chrono::steady_clock::time_point start);
// A file's size, 0 when it is not there.
int64_t FileBytes(const std::filesystem::path& path);

// "monitor: http://127.0.0.1:8080/ ..." when the demo runs a web monitor
// on `monitor_socket` (-1: none).
void PrintMonitorUrl(int monitor_socket, std::ostream& log);

}  // namespace shapesense
