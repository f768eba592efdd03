#include "services/controller/controller_command.h"
#include "runtime/process/signal_thread.h"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <memory>

#include "libs/core/error.h"
#include "runtime/command_line.h"
#include "runtime/lcm/service_loop.h"
#include "runtime/process/systemd_notify.h"
#include "services/controller/controller_client.h"
#include "services/controller/rig_plant_driver.h"

namespace shapesense {
namespace {

constexpr const char* kName = "shapesense-controller";

// The command line as given; an override counts only when its option was given.
struct CommandLine {
  std::filesystem::path config;
  std::string targets, lcm_url, csv, lcm, mode;
  double duration = 0.0;
};

void AddOptions(CLI::App& app, CommandLine& line) {
  app.add_option("--config", line.config,
                 "controller service config (config/controller_client.yaml)")
      ->required();
  app.add_option("--targets", line.targets,
                 "trajectory file (.csv or YAML) or 'stream' (overrides)");
  app.add_option("--mode", line.mode,
                 "open_loop | closed_loop | model_less (overrides the controller options)");
  app.add_option("--lcm-url", line.lcm_url, "LCM provider URL (overrides the config)");
  app.add_option("--log-csv", line.csv, "CSV log path, '' for none (overrides the config)");
  app.add_option("--log-lcm", line.lcm, "LCM log path, '' for none (overrides the config)");
  app.add_option("--duration", line.duration,
                 "stop after this many seconds (overrides the config)");
}

ControllerOverrides OverridesGiven(const CLI::App& app, const CommandLine& line) {
  ControllerOverrides overrides;
  if (app.count("--targets") > 0) overrides.targets = line.targets;
  if (app.count("--mode") > 0) overrides.mode = line.mode;
  if (app.count("--lcm-url") > 0) overrides.lcm_url = line.lcm_url;
  if (app.count("--log-csv") > 0) overrides.log_csv = line.csv;
  if (app.count("--log-lcm") > 0) overrides.log_lcm = line.lcm;
  if (app.count("--duration") > 0) overrides.duration_s = line.duration;
  return overrides;
}

// The actuator link's counters, for the summary.
void PrintLinkHealth(ActuatorDriver& driver, std::ostream& out) {
  const ActuatorHealth health = driver.Health();
  out << kName << ": actuator link (" << driver.description() << "): " << health.connects
      << " connects, " << health.timeouts << " timeouts, " << health.retries << " retries, "
      << health.corrupt_replies << " corrupt replies, " << health.rejected_requests
      << " requests refused, last round trip " << health.round_trip_us << " us" << std::endl;
}

void PrintSummary(ControllerClient& client, const ControllerLog& log, std::ostream& out) {
  const ControllerCounters& c = client.counters();
  const StepRecord& last = client.last_step();
  char seconds[32];
  std::snprintf(seconds, sizeof(seconds), "%.2f", last.time);
  out << kName << ": stopped after " << seconds << " s: " << c.steps << " steps, "
      << c.commands_sent << " commands sent, " << c.held_steps << " steps held; shapes "
      << c.shapes_used << " used, " << c.shapes_without_configuration << " without q, "
      << c.shapes_rejected << " rejected; targets " << c.targets_accepted << " accepted, "
      << c.targets_rejected << " rejected; " << c.messages_rejected << " malformed messages, "
      << c.inputs_dropped << " dropped; " << c.estops << " e-stops; logged " << log.rows()
      << " rows, " << log.events() << " LCM events" << std::endl;
}

}  // namespace

int RunController(const ControllerSetup& setup, const std::atomic<bool>& stop, std::ostream& out) {
  ControllerLog log(setup.client.log.csv, setup.client.log.lcm, setup.actuators.tendons);
  LcmBus bus(setup.client.lcm_url);
  const std::unique_ptr<ActuatorDriver> driver = MakeControllerDriver(setup.actuators, bus);
  ControllerClient client(setup, bus, *driver, log, {}, &out);
  try {
    client.Start();
  } catch (const ActuatorError& e) {
    out << kName << ": failed: actuators (" << driver->description() << "): " << e.what()
        << std::endl;
    driver->Disconnect();
    return kExitFailed;
  }
  // Ready only now: the actuators are connected and the loop starts.
  SystemdNotifier supervisor;
  supervisor.Ready("controlling " + driver->description());
  const int code = RunControllerLoop(client, stop, supervisor);
  PrintSummary(client, log, out);
  PrintLinkHealth(*driver, out);
  if (code != 0) out << kName << ": failed: " << client.error() << std::endl;
  return code;
}

int ControllerMain(int argc, char** argv) {
  const std::atomic<bool>& stop = StopFlagOnSignals();  // before a Connect that may take seconds
  CLI::App app{std::string(kName) +
               ": tendon control on the sensed shape, within safety limits (docs/controller.md)"};
  CommandLine line;
  AddOptions(app, line);
  if (const std::optional<int> exit_code = ParseCommandLine(app, argc, argv)) return *exit_code;
  try {
    return RunController(LoadControllerSetup(line.config, OverridesGiven(app, line)), stop,
                         std::cerr);
  } catch (const InputError& e) {
    std::cerr << kName << ": error: " << e.what() << std::endl;
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << kName << ": failed: " << e.what() << std::endl;
    return kExitFailed;
  }
}

}  // namespace shapesense
