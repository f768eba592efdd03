#pragma once

// The demo's message authentication (docs/security.md): like a rig, the
// demo's programs sign and verify what moves the tendons, with a key of its
// own made in the output folder for each run, unless told to run insecure.
#include <filesystem>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "runtime/lcm/bus_auth.h"
#include "runtime/process/process_group.h"

namespace shapesense {

// `given` with key files: those. Otherwise a new key in
// `setup_dir`/rig.key (replacing the last run's), or, when `given.insecure`,
// none, with a loud warning on `log`.
AuthOptions PrepareDemoAuth(const AuthOptions& given, const std::filesystem::path& setup_dir,
                            std::ostream& log);

// What a program's environment needs to authenticate as `auth` says
// (SHAPESENSE_KEY_FILES or SHAPESENSE_INSECURE).
std::vector<std::pair<std::string, std::string>> AuthEnvironment(const AuthOptions& auth);
void AddAuthEnvironment(const AuthOptions& auth, ProgramSpec* program);

}  // namespace shapesense
