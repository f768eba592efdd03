#include "runtime/rig/rig_units.h"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "runtime/lcm/bus_auth.h"
#include "runtime/process/systemd_unit.h"

namespace shapesense {
namespace {

std::string UnitName(const RigFile& rig, const RigProgram& program) {
  return "shapesense-" + program.program + "-" + rig.name;
}

std::vector<std::string> Command(const RigFile& rig, const RigProgram& program,
                                 const std::filesystem::path& bin_dir) {
  if (program.program == "lcm-logger") {
    // Debian's LCM tools live in /usr/bin; the logger logs the rig network.
    std::vector<std::string> command = {"/usr/bin/lcm-logger", "--lcm-url=" + rig.rig_network};
    command.insert(command.end(), program.args.begin(), program.args.end());
    return command;
  }
  std::vector<std::string> command;
  if (program.program == "rig-status") {
    command = {(bin_dir / "shapesense").string(), "rig", "status", "--rig",
               std::filesystem::absolute(rig.path).string()};
  } else {
    command = {(bin_dir / ("shapesense-" + program.program)).string()};
  }
  if (program.program == "monitor") {
    // The expected programs of its health table are the rig file's.
    command.push_back("--rig");
    command.push_back(std::filesystem::absolute(rig.path).string());
  }
  if (!program.config.empty()) {
    // The monitor's config is the shape service's (its calibration and manipulator).
    command.push_back(program.program == "monitor" ? "--shape-config" : "--config");
    command.push_back(
        std::filesystem::absolute(rig.path.parent_path() / program.config).lexically_normal());
  }
  command.insert(command.end(), program.args.begin(), program.args.end());
  return command;
}

UnitSpec SpecOf(const RigFile& rig, const RigHost& host, const RigProgram& program,
                const std::filesystem::path& bin_dir) {
  UnitSpec spec;
  spec.name = UnitName(rig, program);
  spec.description = "shapesense " + program.program + " of rig " + rig.name + " on " + host.name;
  spec.command = Command(rig, program, bin_dir);
  spec.environment = RigEnvironment(rig, host);
  spec.cpu_affinity = program.cpus;
  spec.realtime_priority = program.realtime_priority;
  spec.notify = program.program != "lcm-logger" && program.program != "rig-status";
  // The sensing chain starts in order on a host; across hosts LCM needs no order.
  if (program.program == "carving")
    spec.after_units = {"shapesense-capture-" + rig.name + ".service"};
  if (program.program == "shape")
    spec.after_units = {"shapesense-carving-" + rig.name + ".service"};
  return spec;
}

}  // namespace

std::vector<std::pair<std::string, std::string>> RigEnvironment(const RigFile& rig,
                                                                const RigHost& host) {
  std::vector<std::pair<std::string, std::string>> environment = {
      {"LCM_DEFAULT_URL", rig.rig_network},
      {"SHAPESENSE_LOCAL_LCM_URL", rig.local_network},
  };
  if (!rig.prefix.empty()) environment.emplace_back("SHAPESENSE_RIG_PREFIX", rig.prefix);
  char warning[32];
  std::snprintf(warning, sizeof(warning), "%g", rig.clock_offset_warning_ms);
  environment.emplace_back("SHAPESENSE_CLOCK_WARNING_MS", warning);
  if (!rig.channels.empty()) {
    environment.emplace_back("SHAPESENSE_CHANNEL_NETWORKS", ChannelNetworks::Format(rig.channels));
  }
  if (!host.keys.empty()) {
    environment.emplace_back("SHAPESENSE_KEY_FILES",
                             FormatKeyFiles({host.keys.begin(), host.keys.end()}));
  }
  if (rig.insecure) environment.emplace_back("SHAPESENSE_INSECURE", "1");
  return environment;
}

std::vector<UnitFile> UnitsForHost(const RigFile& rig, const std::string& host,
                                   const std::filesystem::path& bin_dir) {
  const auto found = std::find_if(rig.hosts.begin(), rig.hosts.end(),
                                  [&](const RigHost& h) { return h.name == host; });
  if (found == rig.hosts.end()) {
    throw std::invalid_argument(rig.path.string() + ": no host '" + host + "' in the rig file");
  }
  std::vector<UnitFile> units;
  for (const RigProgram& program : found->programs) {
    const UnitSpec spec = SpecOf(rig, *found, program, bin_dir);
    units.push_back({spec.name + ".service", FormatUnit(spec)});
  }
  return units;
}

}  // namespace shapesense
