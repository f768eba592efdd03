#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

namespace shapesense {

// `shapesense rig check FILE...`: every problem of each rig file, and of
// the rigs together; returns the number found.
int RunRigCheck(const std::vector<std::filesystem::path>& files, std::ostream& out);

// `shapesense rig units FILE --host NAME --out DIR`: writes the host's
// units; returns how many.
int RunRigUnits(const std::filesystem::path& file, const std::string& host,
                const std::filesystem::path& out_dir, const std::filesystem::path& bin_dir,
                std::ostream& out);

// Registers `shapesense rig` (check, units).
void AddRigCommand(CLI::App& app);

}  // namespace shapesense
