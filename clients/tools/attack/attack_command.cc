#include "clients/tools/attack/attack_command.h"

#include <iostream>
#include <memory>

#include "runtime/file_io.h"
#include "runtime/process/signal_thread.h"

namespace shapesense {

nlohmann::json RunAttack(const AttackOptions& options, const std::atomic<bool>& stop) {
  Attacker attacker(options);
  attacker.Run(stop);
  int64_t sent = 0;
  nlohmann::json by_kind = nlohmann::json::object();
  for (const auto& [kind, count] : attacker.sent()) {
    by_kind[kind] = count;
    sent += count;
  }
  return {{"sent", sent}, {"sent_by_kind", by_kind}};
}

void AddAttackCommand(CLI::App& app) {
  struct Args {
    AttackOptions attack;
    std::filesystem::path report;
  };
  auto args = std::make_shared<Args>();
  CLI::App* command = app.add_subcommand(
      "attack",
      "For the security tests: join the rig network without a key and publish forged, "
      "bit-flipped and replayed targets, shapes and plant commands (docs/security.md)");
  command->add_option("--lcm-url", args->attack.lcm_url, "the rig network (default: LCM's)");
  command->add_option("--prefix", args->attack.prefix, "the rig's channel prefix");
  command->add_option("--rate", args->attack.rate_hz, "messages per second")->capture_default_str();
  command->add_option("--duration", args->attack.duration_s, "seconds (0: until stopped)")
      ->capture_default_str();
  command->add_option("--report", args->report, "where to write what it sent (JSON)");
  command->callback([args] {
    const std::atomic<bool>& stop = StopFlagOnSignals();
    const nlohmann::json report = RunAttack(args->attack, stop);
    std::cout << "attack: sent " << report["sent"] << " messages: " << report["sent_by_kind"].dump()
              << std::endl;
    if (!args->report.empty()) WriteFileAtomically(args->report, report.dump(2) + "\n");
  });
}

}  // namespace shapesense
