#pragma once

// A host's systemd units from the rig file: one per program, Type=notify
// for shapesense's programs (READY once it can work, WATCHDOG from its
// loop), the rig's networks in each unit's environment, the CPU affinity
// and real-time priority the file asks.
#include <filesystem>
#include <string>
#include <vector>

#include "runtime/rig/rig_file.h"

namespace shapesense {

struct UnitFile {
  std::string file_name;  // "shapesense-carving-bench.service"
  std::string text;
};

// `bin_dir`: where shapesense's programs are installed (absolute).
// Throws std::invalid_argument naming an unknown host.
std::vector<UnitFile> UnitsForHost(const RigFile& rig, const std::string& host,
                                   const std::filesystem::path& bin_dir);

// The environment every program of `host` runs with (LCM_DEFAULT_URL,
// SHAPESENSE_LOCAL_LCM_URL, SHAPESENSE_RIG_PREFIX, SHAPESENSE_CHANNEL_NETWORKS,
// SHAPESENSE_CLOCK_WARNING_MS, and the host's SHAPESENSE_KEY_FILES or
// SHAPESENSE_INSECURE).
std::vector<std::pair<std::string, std::string>> RigEnvironment(const RigFile& rig,
                                                                const RigHost& host);

}  // namespace shapesense
