#pragma once

#include <CLI/CLI.hpp>
#include <atomic>
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

struct RigStatusArgs {
  std::filesystem::path rig;  // empty: no expected programs (show whatever is heard)
  std::string lcm_url;        // empty: the rig file's rig network, else LCM_DEFAULT_URL
  bool once = false;          // listen 2.5 s, print, exit
  bool json = false;
  double duration_s = 0.0;  // live: 0 until Ctrl-C
};

// `shapesense rig status`: returns 0 when every expected program is up,
// 1 when one is missing or stale (for scripts).
int RunRigStatus(const RigStatusArgs& args, const std::atomic<bool>& stop, std::ostream& out);

// Registers `shapesense rig` (check, units, status).
void AddRigCommand(CLI::App& app);

}  // namespace shapesense
