#include "clients/tools/demo/experiment_attack.h"

#include "clients/tools/attack/attacker.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "shapesense/configuration_target_t.hpp"
#include "shapesense/shape_t.hpp"
#include "shapesense/tendon_command_t.hpp"

namespace shapesense {
namespace fs = std::filesystem;

nlohmann::json AttackReportToJson(const AttackReport& report) {
  nlohmann::json json = {{"sent", report.sent},
                         {"sent_by_kind", report.sent_by_kind},
                         {"rejected", report.rejected},
                         {"rejected_by_reason", report.rejected_by_reason},
                         {"rejected_by_program", report.rejected_by_program},
                         {"accepted", report.accepted},
                         {"accepted_by_kind", report.accepted_by_kind}};
  if (!report.error.empty()) json["error"] = report.error;
  return json;
}

ProgramSpec AttackerProgram(const DemoSettings& settings, const fs::path& report_file) {
  ProgramSpec spec{"attacker",
                   {(settings.bin_dir / "shapesense").string(), "attack", "--lcm-url",
                    settings.lcm_url, "--report", report_file.string()},
                   "",
                   "",
                   false};
  // It holds no key, whatever this process holds.
  spec.environment = {{"SHAPESENSE_KEY_FILES", ""}, {"SHAPESENSE_INSECURE", "0"}};
  return spec;
}

AttackWitness::AttackWitness(LcmBus& bus) : bus_(bus) {
  bus.Subscribe<configuration_target_t>(
      channels::kTarget, [this](configuration_target_t&& target, const std::string&, int64_t) {
        if (target.source == kAttackerSource) Accepted("target");
      });
  bus.Subscribe<shape_t>(channels::kShape, [this](shape_t&& shape, const std::string&, int64_t) {
    if (shape.trigger_seq >= kForgedTrigger) Accepted("shape");
  });
  bus.Subscribe<tendon_command_t>(channels::kPlantCommand,
                                  [this](tendon_command_t&& command, const std::string&, int64_t) {
                                    if (command.source_trigger_seq >= kForgedTrigger)
                                      Accepted("plant_command");
                                  });
  bus.Subscribe<tendon_command_t>(channels::kTendonCommand,
                                  [this](tendon_command_t&& command, const std::string&, int64_t) {
                                    if (command.source_trigger_seq >= kForgedTrigger)
                                      Accepted("command_from_forged_shape");
                                  });
  bus.Subscribe<service_status_t>(channels::kStatusPattern,
                                  [this](service_status_t&& status, const std::string&, int64_t) {
                                    if (status.auth.empty()) return;
                                    const std::lock_guard lock(mutex_);
                                    statuses_[{status.service, status.pid}] = std::move(status);
                                  });
}

void AttackWitness::Accepted(const std::string& kind) {
  const std::lock_guard lock(mutex_);
  ++accepted_[kind];
}

namespace {

void AddRejections(AttackReport* report, const std::string& program,
                   const std::map<std::string, int64_t>& by_reason) {
  for (const auto& [reason, count] : by_reason) {
    report->rejected += count;
    report->rejected_by_reason[reason] += count;
    report->rejected_by_program[program] += count;
  }
}

}  // namespace

AttackReport AttackWitness::Judge(const fs::path& attacker_report) const {
  AttackReport report;
  try {
    const nlohmann::json sent = nlohmann::json::parse(ReadTextFile(attacker_report));
    report.sent = sent.at("sent").get<int64_t>();
    report.sent_by_kind = sent.at("sent_by_kind");
  } catch (const std::exception& e) {
    report.error = attacker_report.string() + ": " + e.what();
  }
  const std::lock_guard lock(mutex_);
  for (const auto& [key, status] : statuses_) {
    std::map<std::string, int64_t> by_reason;
    for (size_t i = 0; i < status.auth_rejection_reasons.size(); ++i) {
      by_reason[status.auth_rejection_reasons[i]] = status.auth_rejections[i];
    }
    AddRejections(&report, std::get<0>(key), by_reason);
  }
  AddRejections(&report, "shapesense demo", bus_.AuthSnapshot().rejections);
  report.accepted_by_kind = accepted_;
  for (const auto& [kind, count] : accepted_) report.accepted += count;
  return report;
}

}  // namespace shapesense
