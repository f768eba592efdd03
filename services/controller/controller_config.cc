#include "services/controller/controller_config.h"

#include <cmath>
#include <functional>
#include <sstream>

#include "libs/core/error.h"
#include "libs/mechanics/tendon_model.h"
#include "runtime/config_file.h"
#include "runtime/file_io.h"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

// Runs `load`; an InputError from it is prefixed with the client config and
// the key that named the file.
template <class Load>
auto Within(const std::string& source, const std::string& key, Load load) {
  try {
    return load();
  } catch (const InputError& e) {
    throw InputError(DescribeInputError(source, key, e.what()));
  }
}

bool IsCsv(const fs::path& path) {
  std::string extension = path.extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension == ".csv";
}

ControllerClientOptions ReadClientOptions(const fs::path& config,
                                          const ControllerOverrides& overrides) {
  const std::string source = config.string();
  ControllerClientOptions options = LoadOptionsFile<ControllerClientOptions>(config);
  const auto resolve = [&](std::string& path) { path = ResolveConfigPath(config, path).string(); };
  for (std::string* path : {&options.controller, &options.actuators, &options.manipulator,
                            &options.log.csv, &options.log.lcm}) {
    resolve(*path);
  }
  if (!options.stream_targets()) resolve(options.targets);
  // Command-line values are relative to the working directory, as given.
  if (overrides.targets) options.targets = *overrides.targets;
  if (overrides.lcm_url) options.lcm_url = *overrides.lcm_url;
  if (overrides.log_csv) options.log.csv = *overrides.log_csv;
  if (overrides.log_lcm) options.log.lcm = *overrides.log_lcm;
  if (overrides.duration_s) options.duration_s = *overrides.duration_s;
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError(source + ": " + error);
  }
  return options;
}

ResolvedTrajectory LoadTrajectory(const std::string& path, const TendonModel& model,
                                  const ControllerOptions& options) {
  const std::string text = ReadTextFile(path);
  const Trajectory trajectory =
      IsCsv(path) ? ParseTrajectoryCsv(text, path) : ParseTrajectoryYaml(text, path);
  return ResolveTrajectory(trajectory, TargetResolver(model, options), path);
}

}  // namespace

std::string ControllerLogOptions::Validate() const {
  if (!(flush_period_s >= 0.01 && flush_period_s <= 60.0)) {
    return Expected("log.flush_period_s", "0.01-60 s", flush_period_s);
  }
  return "";
}

std::string ControllerClientOptions::Validate() const {
  if (manipulator.empty()) return Expected("manipulator", "a model file", "''");
  if (targets.empty()) return Expected("targets", "a trajectory file or 'stream'", "''");
  if (!(duration_s >= 0.0) || !std::isfinite(duration_s)) {
    return Expected("duration_s", "0 (until stopped) or a positive number of s", duration_s);
  }
  if (!(progress_period_s >= 0.0) || !std::isfinite(progress_period_s)) {
    return Expected("progress_period_s", "0 (none) or a positive number of s", progress_period_s);
  }
  return log.Validate();
}

ControllerSetup LoadControllerSetup(const fs::path& config, const ControllerOverrides& overrides) {
  ControllerSetup setup;
  setup.source = config.string();
  setup.client = ReadClientOptions(config, overrides);
  const ControllerClientOptions& client = setup.client;
  setup.controller = Within(setup.source, "controller",
                            [&] { return LoadOptionsFile<ControllerOptions>(client.controller); });
  if (overrides.mode) {
    ControlMode mode{};
    if (!ParseControlMode(*overrides.mode, &mode)) {
      throw InputError("--mode: expected open_loop, closed_loop or model_less, got '" +
                       *overrides.mode + "'");
    }
    setup.controller.mode = *overrides.mode;
  }
  setup.actuators = Within(setup.source, "actuators",
                           [&] { return LoadOptionsFile<ActuatorOptions>(client.actuators); });
  if (!client.driver.empty()) {
    setup.actuators.driver = client.driver;
    if (const std::string error = setup.actuators.Validate(); !error.empty()) {
      throw InputError(DescribeInputError(setup.source, "driver", error));
    }
  }
  setup.manipulator = Within(setup.source, "manipulator", [&] {
    return ParseManipulatorYaml(ReadTextFile(client.manipulator), client.manipulator);
  });
  const TendonModel model(setup.manipulator);
  if (setup.actuators.tendons != model.num_tendons()) {
    throw InputError(DescribeInputError(
        setup.source, "actuators",
        Expected("tendons", std::to_string(model.num_tendons()) + " (the manipulator's tendons)",
                 setup.actuators.tendons)));
  }
  if (const std::string error = setup.controller.limits.ValidateFor(model.num_tendons());
      !error.empty()) {
    throw InputError(DescribeInputError(setup.source, "controller", "limits." + error));
  }
  if (!client.stream_targets()) {
    setup.trajectory = Within(setup.source, "targets", [&] {
      return LoadTrajectory(client.targets, model, setup.controller);
    });
  }
  return setup;
}

}  // namespace shapesense
