#pragma once

// What `shapesense rig check` finds wrong with a rig file: unknown hosts or
// programs, a channel that nobody publishes or nobody reads, an image
// channel that would cross hosts, networks that would mix, and (over
// several files) two rigs on one multicast group.
#include <string>
#include <vector>

#include "runtime/rig/rig_file.h"

namespace shapesense {

// The channels a program publishes and reads (without the rig prefix).
struct ProgramChannels {
  std::vector<std::string> publishes;
  std::vector<std::string> reads;
  bool reads_rig_network = false;  // a logger: every rig-network channel
};

// The programs a rig file may name; false for any other.
bool IsKnownProgram(const std::string& program);
ProgramChannels ChannelsOf(const std::string& program, const std::vector<std::string>& cameras);

// Every problem, each naming the host, program or channel; empty when none.
std::vector<std::string> CheckRig(const RigFile& rig);
// Rigs that would hear each other: the same rig or local multicast group
// and port (a prefix keeps channels apart, not the traffic each host
// receives and drops).
std::vector<std::string> CheckRigsApart(const std::vector<RigFile>& rigs);

}  // namespace shapesense
