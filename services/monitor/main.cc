// shapesense-monitor: the rig's live web view (see monitor_service.h).
#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>

#include "libs/core/error.h"
#include "runtime/command_line.h"
#include "runtime/process/signal_thread.h"
#include "services/monitor/monitor_service.h"

namespace {

// "cpu 1.234 s in 30.0 s (4.11% of a core)", from getrusage.
std::string CpuLine(double uptime_s) {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const double cpu_s = static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
                       static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) * 1e-6;
  char line[96];
  std::snprintf(line, sizeof(line), "cpu %.3f s in %.1f s (%.2f%% of a core)", cpu_s, uptime_s,
                uptime_s > 0 ? 100.0 * cpu_s / uptime_s : 0.0);
  return line;
}

void AddOptions(CLI::App& app, shapesense::MonitorArgs& args, std::string& lcm_url) {
  app.add_option("--http", args.http, "HOST:PORT the page is served on")->capture_default_str();
  app.add_option("--lcm-url", lcm_url, "the rig network (default: LCM_DEFAULT_URL)");
  app.add_option("--calibration", args.calibration,
                 "the cameras' calibration (rig YAML), to project the shape into the pictures");
  app.add_option("--rig", args.rig, "rig file (hosts and programs): the programs expected");
  app.add_option("--shape-config", args.shape_config,
                 "the shape service's config: its calibration and manipulator, to draw targets");
  app.add_option("--assets", args.assets, "the page's folder (default: beside the program)");
  app.add_option("--estop-token-file", args.estop_token_file,
                 "file (mode 600) with the token that enables the page's e-stop button");
  app.add_option("--duration", args.duration_s, "stop after this many seconds");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"shapesense-monitor: the rig's live web view (docs/monitor.md)"};
  shapesense::MonitorArgs args;
  std::string lcm_url;
  AddOptions(app, args, lcm_url);
  if (const std::optional<int> exit_code = shapesense::ParseCommandLine(app, argc, argv)) {
    return *exit_code;
  }
  if (app.count("--lcm-url") > 0) args.lcm_url = lcm_url;
  try {
    const auto status = shapesense::RunMonitor(args, shapesense::StopFlagOnSignals(), std::cout);
    // Its own cost over the whole run (what the monitor bench reads).
    std::cerr << "shapesense-monitor: stopped; " << status.received << " messages received, "
              << status.published << " sent to browsers; " << CpuLine(status.uptime_s) << '\n';
  } catch (const shapesense::InputError& e) {
    std::cerr << "shapesense-monitor: error: " << e.what() << '\n';
    return shapesense::kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "shapesense-monitor: failed: " << e.what() << '\n';
    return shapesense::kExitFailed;
  }
  return 0;
}
