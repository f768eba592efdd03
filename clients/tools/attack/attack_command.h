#pragma once

// `shapesense attack`: the hostile process of the security tests and of
// `shapesense demo --attacker` (attacker.h). It holds no key; what it sent
// goes to --report as JSON {"sent": N, "sent_by_kind": {...}}.
#include <CLI/CLI.hpp>
#include <atomic>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "clients/tools/attack/attacker.h"

namespace shapesense {

// Attacks until `stop` or the duration; the report's JSON.
nlohmann::json RunAttack(const AttackOptions& options, const std::atomic<bool>& stop);

void AddAttackCommand(CLI::App& app);

}  // namespace shapesense
