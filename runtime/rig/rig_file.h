#pragma once

// The rig file (config/rig.yaml, docs/rig.md): the rig's networks and
// cameras, its hosts, and the programs each host runs with their configs.
// `shapesense rig check` validates it (rig_check.h), `shapesense rig units`
// turns a host's part into systemd units (rig_units.h).
#include <filesystem>
#include <string>
#include <vector>

#include "runtime/lcm/channel_networks.h"

namespace shapesense {

struct RigProgram {
  std::string program;  // rig-sim, capture, carving, shape, controller, lcm-logger, rig-status
  std::string config;   // as written (relative: to the rig file's folder); may be empty
  std::vector<std::string> args;
  std::vector<int> cpus;
  int realtime_priority = 0;  // 0: normal; 1-99: SCHED_FIFO
};

struct RigHost {
  std::string name;       // its host name (gethostname): what its messages carry
  std::string interface;  // the rig network's interface, e.g. eth1
  // The rig key files this host holds (docs/security.md): one, or two while
  // a key is rotated in (the second, which signs). Absolute paths on the host.
  std::vector<std::string> keys;
  std::vector<RigProgram> programs;
};

struct RigFile {
  std::filesystem::path path;  // where it was read from (configs are relative to it)
  std::string name;
  std::string prefix;
  std::string rig_network;    // udpm://group:port?ttl=1
  std::string local_network;  // udpm://group:port?ttl=0
  double clock_offset_warning_ms = 1.0;
  // Runs without message authentication (loudly; docs/security.md).
  bool insecure = false;
  std::vector<std::string> cameras;
  std::vector<ChannelRoute> channels;  // overrides of the channel networks
  std::vector<RigHost> hosts;
};

// Parses the YAML text; InputError naming `source` and the key on
// malformed YAML or a value of the wrong kind (what rig_check.h finds
// wrong with well-formed content is a list of problems instead).
RigFile ParseRigFile(const std::string& text, const std::filesystem::path& source);

}  // namespace shapesense
