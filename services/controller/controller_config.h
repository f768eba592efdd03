#pragma once

// The controller service's config (config/controller_client.yaml;
// docs/controller.md): which controller options, actuators, manipulator
// model and targets it runs with, where it logs, which LCM network. All of
// it is read and checked, the trajectory resolved against the model, before
// any log, bus or driver is opened.

#include <filesystem>
#include <optional>
#include <string>

#include "libs/control/control_options.h"
#include "libs/control/targets.h"
#include "libs/mechanics/manipulator_options.h"
#include "services/controller/actuators/actuator_options.h"

namespace shapesense {

struct ControllerLogOptions {
  // One row per control step (empty: none).
  std::string csv = "../controller-output/controller_log.csv";
  // LCM log of the commands, actuator states and sensed configurations (empty: none).
  std::string lcm = "../controller-output/controller_log.lcmlog";
  // Both are flushed this often while running, and always when the controller stops.
  double flush_period_s = 1.0;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("csv", csv, "CSV log, one row per control step, relative to this file (empty: none)");
    visit("lcm", lcm,
          "LCM log of commands, actuator states and sensed q, relative to this file (empty: none)");
    visit("flush_period_s", flush_period_s,
          "logs are flushed this often, and on every stop, s (0.01-60)");
  }
  std::string Validate() const;
};

struct ControllerClientOptions {
  // Files relative to this config's folder. Empty controller / actuators:
  // their documented defaults.
  std::string controller = "controller.yaml";
  std::string actuators = "actuators.yaml";
  // Overrides the actuators file's driver (empty: keep it), so that one
  // actuators file serves the rig and the virtual rig.
  std::string driver;
  std::string manipulator = "manipulator.yaml";
  // A trajectory (.csv, else YAML; libs/control/targets.h), or "stream":
  // targets come on SHAPESENSE_TARGET.
  std::string targets = "targets.yaml";
  std::string lcm_url;  // empty: LCM_DEFAULT_URL or LCM's default
  ControllerLogOptions log;
  double duration_s = 0.0;         // 0: until SIGINT / SIGTERM
  double progress_period_s = 5.0;  // a progress line on stderr this often (0: none)

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("controller", controller,
          "controller options (modes, gains, limits, watchdog), relative to this file "
          "(empty: the defaults)");
    visit("actuators", actuators,
          "actuator driver options, relative to this file (empty: the defaults)");
    visit("driver", driver,
          "overrides the actuators file's driver: serial | socketcan | simulated | rig "
          "(empty: keep it)");
    visit("manipulator", manipulator, "manipulator model file, relative to this file");
    visit("targets", targets,
          "trajectory file (.csv, else YAML), relative to this file, or 'stream' (targets on "
          "SHAPESENSE_TARGET)");
    visit("lcm_url", lcm_url, "LCM provider URL (empty: LCM_DEFAULT_URL or LCM's default)");
    visit("log", log, "where every step is logged");
    visit("duration_s", duration_s, "stop after this long, s (0: until SIGINT or SIGTERM)");
    visit("progress_period_s", progress_period_s,
          "a progress line on stderr this often, s (0: only changes of state)");
  }
  std::string Validate() const;
  bool stream_targets() const { return targets == "stream"; }
};

// What the command line may override (paths relative to the working directory).
struct ControllerOverrides {
  std::optional<std::string> targets;
  std::optional<std::string> mode;  // the controller options' mode: "open_loop", ...
  std::optional<std::string> lcm_url;
  std::optional<std::string> log_csv;
  std::optional<std::string> log_lcm;
  std::optional<double> duration_s;
};

// Everything the client runs with, loaded and checked.
struct ControllerSetup {
  std::string source;              // the client config file, for messages
  ControllerClientOptions client;  // every path resolved
  ControllerOptions controller;
  ActuatorOptions actuators;
  ManipulatorOptions manipulator;
  ResolvedTrajectory trajectory;  // empty when client.stream_targets()
};

// Reads the client config and every file it names, checks them against
// each other (one actuator per tendon of the model, the limits for the
// model) and resolves the trajectory. Throws InputError("config: key: what"),
// e.g. "client.yaml: targets: t.csv: line 7: expected 5 columns, got 4".
ControllerSetup LoadControllerSetup(const std::filesystem::path& config,
                                    const ControllerOverrides& overrides = {});

}  // namespace shapesense
