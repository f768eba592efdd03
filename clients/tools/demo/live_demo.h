#pragma once

// `shapesense demo`: the live pipeline on the virtual rig, as separate
// programs over LCM, for a set time. It makes the rig file and the
// backgrounds (the rig-sim showing the backdrop alone, `shapesense-capture
// background`), then runs the rig-sim, the capture service, the carving and
// shape services and lcm-logger; this process scores the shapes against the
// rig's truth as `shapesense monitor` does (LiveScorer). At the end it
// replays the log (`shapesense replay`) and checks that the replay gives the
// live shapes. The network (a private namespace or not) is the caller's.
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <ostream>

#include "clients/tools/demo/demo_plan.h"
#include "clients/tools/demo/demo_report.h"

namespace shapesense {

// How the live demo shows its progress.
enum class DemoProgress {
  kOff,
  kLines,     // a line every few seconds (a log)
  kTerminal,  // one line redrawn in place
};

struct LiveDemoArgs {
  std::filesystem::path out = "demo-output";
  double duration_s = 20.0;  // measured run, from the capture service's start
  double rate_hz = 30.0;     // software trigger rate
  uint32_t seed = 7;         // synthetic rig and pixel noise
  DemoCameras cameras = DemoCameras::kGigE;
  std::string network = "private network namespace";  // for the report
  std::filesystem::path bin_dir;     // the shapesense programs; empty: beside this executable
  std::filesystem::path lcm_logger;  // empty: lcm-logger on $PATH
  bool replay = true;                // replay the log and compare
  DemoProgress progress = DemoProgress::kLines;
  // Message authentication: key files, or insecure; neither: a new key in
  // out/setup/rig.key (demo_auth.h).
  AuthOptions auth;
  // The web monitor's listening socket in the host's network (DemoSettings); -1: none.
  int monitor_socket = -1;
};

// Runs it; `stop` (Ctrl-C) ends the run early, cleanly: every program
// stopped, the log closed, the summary of what ran printed and written.
// Writes out/report.json (LiveReportToJson), out/pipeline.lcm,
// out/replay_shapes.jsonl, out/logs/<program>.log and out/setup/. Throws
// ProgramFailure naming a program that is missing, failed to start or ended
// early (with its last output; report.json says so too), InputError on bad
// arguments.
LiveDemoReport RunLiveDemo(const LiveDemoArgs& args, const std::atomic<bool>& stop,
                           std::ostream& log);

// The folder of this executable (/proc/self/exe), where the other programs are.
std::filesystem::path ExecutableDir();

}  // namespace shapesense
