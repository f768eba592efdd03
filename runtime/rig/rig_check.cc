#include "runtime/rig/rig_check.h"

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>

#include "runtime/lcm/channels.h"
#include "runtime/lcm/lcm_url.h"

namespace shapesense {
namespace {

namespace ch = channels;

std::vector<std::string> PerCamera(std::string (*channel)(const std::string&),
                                   const std::vector<std::string>& cameras) {
  std::vector<std::string> names;
  names.reserve(cameras.size());
  for (const std::string& camera : cameras) names.push_back(channel(camera));
  return names;
}

// Channels nobody need publish (an operator's e-stop, the virtual rig's
// plant link and truth) or read (monitoring silhouettes, command echoes).
bool OptionalToPublish(const std::string& channel) {
  return channel == ch::kEstop || channel == ch::kPlantCommand || channel == ch::kPlantState ||
         channel == ch::kTruth || channel == ch::kTarget || channel == ch::kTendonCommand ||
         channel == ch::kTendonState || channel.rfind("SHAPESENSE_PREVIEW_", 0) == 0;
}
bool MustBeRead(const std::string& channel) {
  return channel.rfind("SHAPESENSE_IMAGE_", 0) == 0 || channel == ch::kVoxels ||
         channel == ch::kSilhouettes || channel == ch::kShape;
}

struct Endpoint {
  std::string host;
  std::string program;
  std::string Name() const { return program + " on " + host; }
};

struct ChannelUse {
  std::vector<Endpoint> publishers;
  std::vector<Endpoint> readers;
};

std::map<std::string, ChannelUse> ChannelUses(const RigFile& rig, const ChannelNetworks& networks) {
  std::map<std::string, ChannelUse> uses;
  std::vector<Endpoint> loggers;
  for (const RigHost& host : rig.hosts) {
    for (const RigProgram& program : host.programs) {
      if (!IsKnownProgram(program.program)) continue;
      const ProgramChannels channels = ChannelsOf(program.program, rig.cameras);
      const Endpoint endpoint{host.name, program.program};
      for (const std::string& c : channels.publishes) uses[c].publishers.push_back(endpoint);
      for (const std::string& c : channels.reads) uses[c].readers.push_back(endpoint);
      if (channels.reads_rig_network) loggers.push_back(endpoint);
    }
  }
  for (auto& [channel, use] : uses) {
    if (networks.Of(channel) != Network::kRig) continue;
    use.readers.insert(use.readers.end(), loggers.begin(), loggers.end());
  }
  return uses;
}

void CheckNetworks(const RigFile& rig, std::vector<std::string>* problems) {
  const auto problem = [&](const std::string& text) { problems->push_back(text); };
  if (!IsUdpm(rig.rig_network) || TtlOf(rig.rig_network) < 1) {
    problem("rig.rig_network '" + rig.rig_network +
            "': expected udpm://GROUP:PORT?ttl=1 (the rig network crosses the hosts' switch)");
  }
  if (!IsUdpm(rig.local_network) || TtlOf(rig.local_network) != 0) {
    problem("rig.local_network '" + rig.local_network +
            "': expected udpm://GROUP:PORT?ttl=0 (images never leave their host)");
  }
  if (!IsUdpm(rig.rig_network) || !IsUdpm(rig.local_network)) return;
  const UdpmUrl shared = SplitUdpm(rig.rig_network);
  const UdpmUrl local = SplitUdpm(rig.local_network);
  const int last_image_port = local.port + static_cast<int>(rig.cameras.size());
  if (shared.port >= local.port && shared.port <= last_image_port) {
    problem("rig.rig_network's port " + std::to_string(shared.port) +
            " is among the local network's ports " + std::to_string(local.port) + "-" +
            std::to_string(last_image_port) +
            " (its own and one per camera's images): every rig-network listener would receive "
            "the host's images");
  }
}

// Every host holds the rig key (or two during a rotation) unless the rig
// runs insecure; the files themselves are on the hosts, checked there by
// the programs that read them (0600, well formed).
void CheckKeys(const RigFile& rig, const RigHost& host, std::vector<std::string>* problems) {
  const std::string where = "hosts." + host.name + ".keys";
  if (host.keys.empty() && !rig.insecure) {
    problems->push_back(where +
                        ": missing (the rig key file this host holds, `shapesense keygen`; "
                        "or rig.insecure: true, docs/security.md)");
  }
  if (host.keys.size() > 2) {
    problems->push_back(where + ": at most two (the key in use and the one rotated in)");
  }
  for (const std::string& key : host.keys) {
    std::string named = where;
    named.append(": '").append(key).append("'");
    if (!std::filesystem::path(key).is_absolute()) {
      problems->push_back(named + " is not an absolute path");
    }
    if (key.find(':') != std::string::npos) {
      problems->push_back(named + " contains ':' (SHAPESENSE_KEY_FILES' separator)");
    }
  }
}

void CheckHosts(const RigFile& rig, std::vector<std::string>* problems) {
  std::set<std::string> names;
  for (const RigHost& host : rig.hosts) {
    if (!names.insert(host.name).second) problems->push_back("hosts." + host.name + ": twice");
    if (host.interface.empty()) {
      problems->push_back("hosts." + host.name + ".interface: missing (the rig network's NIC)");
    }
    CheckKeys(rig, host, problems);
    for (const RigProgram& program : host.programs) {
      const std::string where = "hosts." + host.name + ": " + program.program;
      if (!IsKnownProgram(program.program)) {
        problems->push_back(where +
                            ": unknown program (rig-sim, capture, carving, shape, "
                            "controller, lcm-logger, rig-status, monitor)");
      }
      if (program.realtime_priority < 0 || program.realtime_priority > 99) {
        problems->push_back(where + ": realtime_priority: expected 0-99");
      }
      const std::filesystem::path config = rig.path.parent_path() / program.config;
      if (!program.config.empty() && !std::filesystem::exists(config)) {
        problems->push_back(where + ": config " + config.string() + " does not exist");
      }
    }
  }
}

std::string Names(const std::vector<Endpoint>& endpoints) {
  std::string text;
  for (const Endpoint& endpoint : endpoints) text += (text.empty() ? "" : ", ") + endpoint.Name();
  return text;
}

void CheckChannels(const RigFile& rig, std::vector<std::string>* problems) {
  const ChannelNetworks networks(rig.channels);
  for (const auto& [channel, use] : ChannelUses(rig, networks)) {
    if (use.publishers.empty() && !OptionalToPublish(channel)) {
      problems->push_back(channel + ": nobody publishes it (read by " + Names(use.readers) + ")");
    }
    if (use.readers.empty() && !use.publishers.empty() && MustBeRead(channel)) {
      problems->push_back(channel + ": nobody reads it (published by " + Names(use.publishers) +
                          ")");
    }
    const bool image = channel.rfind("SHAPESENSE_IMAGE_", 0) == 0;
    if (image && networks.Of(channel) != Network::kLocal) {
      problems->push_back(channel +
                          ": an image channel routed to the rig network (images "
                          "must stay on their host: docs/rig.md)");
    }
    if (networks.Of(channel) != Network::kLocal) continue;
    for (const Endpoint& publisher : use.publishers) {
      for (const Endpoint& reader : use.readers) {
        if (reader.host == publisher.host) continue;
        problems->push_back(channel + ": would cross hosts (" + publisher.Name() + " to " +
                            reader.Name() + "), but it travels on the host-local network");
      }
    }
  }
}

}  // namespace

bool IsKnownProgram(const std::string& program) {
  static const std::set<std::string> known = {"rig-sim",    "capture",    "carving",    "shape",
                                              "controller", "lcm-logger", "rig-status", "monitor"};
  return known.count(program) > 0;
}

ProgramChannels ChannelsOf(const std::string& program, const std::vector<std::string>& cameras) {
  if (program == "rig-sim") return {{ch::kTruth, ch::kPlantState}, {ch::kPlantCommand}};
  if (program == "capture") {
    std::vector<std::string> publishes = PerCamera(&ch::Image, cameras);
    for (const std::string& preview : PerCamera(&ch::Preview, cameras))
      publishes.push_back(preview);
    return {publishes, {}};
  }
  if (program == "carving") {
    std::vector<std::string> publishes = PerCamera(&ch::Silhouette, cameras);
    publishes.insert(publishes.end(), {ch::kSilhouettes, ch::kVoxels});
    return {publishes, PerCamera(&ch::Image, cameras)};
  }
  if (program == "shape") return {{ch::kShape}, {ch::kVoxels, ch::kSilhouettes}};
  if (program == "controller") {
    return {{ch::kTendonCommand, ch::kTendonState, ch::kPlantCommand},
            {ch::kShape, ch::kTarget, ch::kEstop, ch::kPlantState}};
  }
  if (program == "lcm-logger") return {{}, {}, true};
  if (program == "rig-status") return {{}, {ch::kShape}};
  if (program == "monitor") {
    // What it needs; the compact silhouettes and the voxels it shows when
    // they travel on its network (a rig may keep them on the camera host).
    std::vector<std::string> reads = PerCamera(&ch::Preview, cameras);
    reads.insert(reads.end(), {ch::kShape, ch::kTarget, ch::kTendonCommand, ch::kTendonState,
                               ch::kEstop, ch::kTruth});
    return {{ch::kEstop}, reads};
  }
  return {};
}

std::vector<std::string> CheckRig(const RigFile& rig) {
  std::vector<std::string> problems;
  const std::string source = rig.path.string() + ": ";
  if (rig.name.empty()) problems.push_back("rig.name: missing");
  if (!std::all_of(rig.prefix.begin(), rig.prefix.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
      })) {
    problems.push_back("rig.prefix '" + rig.prefix + "': only letters, digits and '_'");
  }
  if (rig.cameras.empty()) problems.push_back("rig.cameras: none");
  if (!(rig.clock_offset_warning_ms > 0)) {
    problems.push_back("rig.clock_offset_warning_ms: expected a positive number of ms");
  }
  if (rig.hosts.empty()) problems.push_back("hosts: none");
  CheckNetworks(rig, &problems);
  CheckHosts(rig, &problems);
  CheckChannels(rig, &problems);
  for (std::string& problem : problems) problem.insert(0, source);
  return problems;
}

std::vector<std::string> CheckRigsApart(const std::vector<RigFile>& rigs) {
  std::vector<std::string> problems;
  std::map<std::string, std::string> owner;  // group:port -> rig
  for (const RigFile& rig : rigs) {
    for (const std::string& url : {rig.rig_network, rig.local_network}) {
      if (!IsUdpm(url)) continue;
      const std::string group = GroupAndPort(url);
      const auto [it, fresh] = owner.emplace(group, rig.name + " (" + rig.path.string() + ")");
      if (!fresh && it->second != rig.name + " (" + rig.path.string() + ")") {
        problems.push_back("rigs " + it->second + " and " + rig.name + " (" + rig.path.string() +
                           ") share the multicast group " + group +
                           ": give each rig its own group and ports");
      }
    }
  }
  return problems;
}

}  // namespace shapesense
