#pragma once

// `shapesense keygen --out FILE [--id N]`: a new 256-bit message key
// (docs/security.md), written 0600, never over an existing file.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <filesystem>
#include <ostream>

namespace shapesense {

// Writes the key and says where (its id, never its secret). `id` 0: the
// current time in seconds, so that a newer key has a larger id.
uint32_t RunKeygen(const std::filesystem::path& out, uint32_t id, std::ostream& log);

void AddKeygenCommand(CLI::App& app);

}  // namespace shapesense
