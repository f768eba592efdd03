#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace shapesense {

// The documented default options of a component as YAML (every key with its
// meaning and default): what config/*.yaml hold. Empty for an unknown name.
std::string DocumentedDefaults(const std::string& component);

// Registers `shapesense config COMPONENT`.
void AddConfigCommand(CLI::App& app);

}  // namespace shapesense
