#pragma once

// The three-host side of the closed-loop experiment (`shapesense demo
// --hosts 3`, demo_hosts.h): the hosts' layout from a checked rig file,
// what the rig network carried, the faults made on the hosts and how they
// went, and their part of report.json.
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "clients/tools/demo/closed_loop_experiment.h"
#include "clients/tools/demo/demo_hosts.h"
#include "clients/tools/demo/demo_plan.h"
#include "clients/tools/demo/experiment_faults.h"
#include "runtime/process/process_group.h"
#include "runtime/process/virtual_hosts.h"
#include "runtime/rig/rig_file.h"
#include "shapesense/service_status_t.hpp"

namespace shapesense {

// The three hosts' side of the experiment (demo_hosts.h): the rig file,
// checked as `shapesense rig check` would, and each program put on its host
// with the file's environment. With one host, Place() changes nothing.
class HostLayout {
 public:
  // Writes and checks the rig file in `setup_dir` (InputError naming each
  // problem) when `args` has hosts; every host holds `auth`'s keys.
  HostLayout(const ExperimentArgs& args, const std::filesystem::path& setup_dir,
             const std::vector<std::string>& cameras, const AuthOptions& auth);

  bool active() const { return hosts_ != nullptr; }
  const VirtualHosts& hosts() const { return *hosts_; }
  void Place(ProgramSpec* spec) const {
    if (hosts_ != nullptr) PlaceOnDemoHost(*hosts_, rig_, spec);
  }
  // `shapesense rig status --once --json` on the operator host.
  ProgramSpec RigStatus(const std::filesystem::path& shapesense) const;

 private:
  const VirtualHosts* hosts_;
  std::filesystem::path rig_file_;
  RigFile rig_;
};

// The last JSON document a program printed into its log (`rig status
// --json` prints one, indented, starting with a line "{"); null when none.
nlohmann::json LastJson(const std::filesystem::path& log);

// The config folder of `controller_config` copied into `dir`, the plant
// link's timeout widened past the control link's fault: the controller of
// a run on three hosts. Returns the copy of `controller_config`.
std::filesystem::path ControllerConfigForHosts(const std::filesystem::path& controller_config,
                                               const std::filesystem::path& dir);

// lcm-logger on the operator host rotates its files (--rotate), as the rig
// file's does: it writes <log>.0 (a restart goes on in it) and moves a full
// one to .1 and on. Removes what an earlier run left.
void RotateLogs(DemoPlan& plan);
// The logger's continuity across its restarts (the faults'), from its files.
void JudgeLogs(const std::filesystem::path& log, RigNetworkReport& rig);

// The faults of `args` acting on the hosts' link and the group's programs.
FaultInjector MakeFaultInjector(const ExperimentArgs& args, const DemoPlan& plan,
                                ProcessGroup& processes);

// What the faults are judged by once the run is over.
struct FaultEvidence {
  std::filesystem::path steps_csv;   // the controller's step log
  std::vector<int64_t> shape_times;  // when the run's shapes arrived (µs)
  int shape_restarts = 0;            // by the group
  double hold_age_s = 0;             // the controller's watchdog
  int64_t origin_utime = 0;          // the run's start
  int64_t end_utime = 0;
};
void JudgeFaults(const FaultInjector& injector, const FaultEvidence& evidence,
                 RigNetworkReport& rig);

// Each host's measured offsets of the others, ms, from its newest status.
std::map<std::string, std::map<std::string, double>> MeasuredClockOffsetsMs(
    const std::map<std::string, service_status_t>& status_by_host);

RigNetworkReport DescribeHosts(const VirtualHosts& hosts, const DemoPlan& plan,
                               const std::vector<std::string>& modes);

// What a three-host run measures of its rig network while the runs go on.
class RigNetworkWatch {
 public:
  // Listens on the operator host's rig network from now (with hosts).
  explicit RigNetworkWatch(const HostLayout& layout);

  // The control host's bytes from now.
  void Begin();
  // The bytes per second since Begin(), every channel heard, the images among them.
  void End(RigNetworkReport& rig) const;

 private:
  const HostLayout& layout_;
  std::unique_ptr<NetworkCensus> census_;
  VirtualHosts::LinkBytes begin_;
  int64_t begin_utime_ = 0;
};

// The three-host fields of report.json.
void AddRigToJson(const RigNetworkReport& rig, nlohmann::json& json);

}  // namespace shapesense
