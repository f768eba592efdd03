#include "runtime/lcm/service_main.h"
#include "runtime/process/signal_thread.h"

#include <CLI/CLI.hpp>
#include <iostream>

#include "libs/core/error.h"
#include "runtime/command_line.h"
#include "runtime/lcm/service_loop.h"

namespace shapesense {
namespace {

void AddServiceOptions(CLI::App& app, ServiceArgs& args, std::string& lcm_url,
                       const std::string& example_config) {
  app.add_option("--config", args.config, "service config (" + example_config + ")");
  app.add_option("--lcm-url", lcm_url, "LCM provider URL (overrides the config)");
  app.add_option("--rig", args.rig, "rig file (overrides the config)");
  app.add_option("--backgrounds", args.backgrounds,
                 "folder of <camera>.png (overrides the config)");
  app.add_option("--duration", args.duration_s,
                 "stop after this many seconds (default: run until stopped)");
}

void PrintCounters(const std::string& name, const service_status_t& status) {
  std::cerr << name << ": stopped; " << status.received << " received, " << status.published
            << " published, " << status.dropped << " dropped, " << status.rejected << " rejected, "
            << status.errors << " errors\n";
}

}  // namespace

int ServiceMain(int argc, char** argv, const std::string& name, const std::string& description,
                const std::string& example_config, const RunServiceFunction& run) {
  KeepFreedMemoryForReuse();
  CLI::App app{name + ": " + description};
  ServiceArgs args;
  std::string lcm_url;
  AddServiceOptions(app, args, lcm_url, example_config);
  if (const std::optional<int> exit_code = ParseCommandLine(app, argc, argv)) return *exit_code;
  if (app.count("--lcm-url") > 0) args.lcm_url = lcm_url;
  try {
    PrintCounters(name, run(args, StopFlagOnSignals(), std::cerr));
  } catch (const InputError& e) {
    std::cerr << name << ": error: " << e.what() << '\n';
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << name << ": failed: " << e.what() << '\n';
    return kExitFailed;
  }
  return 0;
}

}  // namespace shapesense
