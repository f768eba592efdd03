#include "clients/tools/demo/demo_hosts.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

#include "runtime/rig/rig_units.h"

namespace shapesense {

std::vector<VirtualHostSpec> DemoHostSpecs(double camera_clock_offset_ms, int cameras) {
  return {{kCameraHostName, camera_clock_offset_ms, cameras},
          {kControlHostName, 0.0, 0},
          {kOperatorHostName, 0.0, 0}};
}

std::string DemoRigFileText(const std::vector<std::string>& cameras,
                            const std::string& local_network, const AuthOptions& auth) {
  // Every host holds the run's key (on a rig, a copy each).
  std::string keys = "[";
  for (const std::filesystem::path& key : auth.key_files) {
    if (keys.size() > 1) keys += ", ";
    keys += std::filesystem::absolute(key).string();
  }
  keys += "]";
  std::ostringstream out;
  out << "# Written by `shapesense demo --hosts 3`: the virtual rig's three hosts\n"
         "# (config/rig.yaml documents every key).\n"
         "rig:\n  name: demo\n  prefix: \"\"\n  rig_network: "
      << kDemoRigNetworkUrl << "\n  local_network: " << local_network
      << "\n  clock_offset_warning_ms: 1\n  insecure: " << (auth.insecure ? "true" : "false")
      << "\n  cameras: [";
  for (size_t i = 0; i < cameras.size(); ++i) out << (i > 0 ? ", " : "") << cameras[i];
  // Carving and shape share the camera host: their voxel cloud and edge
  // data need not cross the bridge.
  out << "]\n  channels: {SHAPESENSE_VOXELS: local, SHAPESENSE_SILHOUETTES: local}\n"
         "hosts:\n"
         "  camera:\n    interface: rig0\n    keys: "
      << keys
      << "\n    programs:\n"
         "      - {program: rig-sim}\n      - {program: capture}\n"
         "      - {program: carving}\n      - {program: shape}\n"
         "  control:\n    interface: rig0\n    keys: "
      << keys
      << "\n    programs:\n      - {program: controller}\n"
         "  operator:\n    interface: rig0\n    keys: "
      << keys
      << "\n    programs:\n"
         "      - {program: lcm-logger}\n      - {program: rig-status}\n";
  return out.str();
}

std::string DemoHostOf(const std::string& program_name) {
  for (const char* prefix : {"rig-sim", "capture", "carving", "shape"}) {
    if (program_name.starts_with(prefix)) return kCameraHostName;
  }
  if (program_name.starts_with("controller")) return kControlHostName;
  // The attacker is a laptop on the operator's side of the switch.
  if (program_name.starts_with("lcm-logger") || program_name.starts_with("rig-status") ||
      program_name == "attacker" || program_name == "monitor") {
    return kOperatorHostName;
  }
  throw std::invalid_argument("demo --hosts: no host for the program '" + program_name + "'");
}

void PlaceOnDemoHost(const VirtualHosts& hosts, const RigFile& rig, ProgramSpec* spec) {
  const std::string host = DemoHostOf(spec->name);
  const auto rig_host = std::find_if(rig.hosts.begin(), rig.hosts.end(),
                                     [&](const RigHost& h) { return h.name == host; });
  if (rig_host == rig.hosts.end()) {
    throw std::invalid_argument("demo --hosts: the rig file has no host '" + host + "'");
  }
  // The rig file's environment replaces what the plan set (the same keys).
  for (auto& variable : RigEnvironment(rig, *rig_host)) {
    std::erase_if(spec->environment, [&](const auto& set) { return set.first == variable.first; });
    spec->environment.push_back(std::move(variable));
  }
  hosts.PlaceOn(host, spec);
}

NetworkCensus::NetworkCensus(const std::string& url) : lcm_(url) {
  if (!lcm_.good()) throw std::runtime_error("cannot open LCM on " + url);
  lcm_.subscribe(".*", &NetworkCensus::OnMessage, this);
  thread_ = std::thread([this] {
    while (!done_.load()) lcm_.handleTimeout(100);
  });
}

NetworkCensus::~NetworkCensus() {
  done_ = true;
  thread_.join();
}

std::map<std::string, int64_t> NetworkCensus::Counts() const {
  const std::lock_guard lock(mutex_);
  return counts_;
}

void NetworkCensus::OnMessage(const lcm::ReceiveBuffer*, const std::string& channel) {
  const std::lock_guard lock(mutex_);
  ++counts_[channel];
}

}  // namespace shapesense
