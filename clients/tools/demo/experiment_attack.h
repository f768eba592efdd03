#pragma once

// `shapesense demo --attacker` (docs/security.md): the attacker of
// clients/tools/attack joins the rig network for every run of the
// experiment, and this is what came of it. Sent: the attacker's own count.
// Rejected: what the receivers holding the key refused, from their
// statuses (each controller run's last, the rig-sim's, this process's own
// bus), by reason and by program. Accepted: forgeries that a receiver acted
// on, by their markers: a forged target, shape or plant command that reached
// a handler of this process's bus (which verifies as the controller's does),
// or a tendon command the controller computed from a forged shape.
#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>

#include "clients/tools/demo/demo_plan.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/process/process_group.h"
#include "shapesense/service_status_t.hpp"

namespace shapesense {

struct AttackReport {
  int64_t sent = 0;
  nlohmann::json sent_by_kind = nlohmann::json::object();
  int64_t rejected = 0;
  std::map<std::string, int64_t> rejected_by_reason;
  std::map<std::string, int64_t> rejected_by_program;
  int64_t accepted = 0;
  std::map<std::string, int64_t> accepted_by_kind;
  std::string error;  // the attacker's report could not be read
};

nlohmann::json AttackReportToJson(const AttackReport& report);

// `shapesense attack` on the experiment's rig network, its report in `report_file`.
ProgramSpec AttackerProgram(const DemoSettings& settings, const std::filesystem::path& report_file);

// Watches, on the experimenter's bus, for forgeries that got through and
// for the receivers' statuses.
class AttackWitness {
 public:
  explicit AttackWitness(LcmBus& bus);

  // The attacker's report file read, the receivers' counts added up.
  AttackReport Judge(const std::filesystem::path& attacker_report) const;

 private:
  void Accepted(const std::string& kind);

  LcmBus& bus_;
  mutable std::mutex mutex_;
  std::map<std::string, int64_t> accepted_;
  // Each receiver process's newest status, by service and pid (the
  // controller runs once per mode).
  std::map<std::tuple<std::string, int32_t>, service_status_t> statuses_;
};

}  // namespace shapesense
