#include "clients/tools/demo/demo_auth.h"

#include "runtime/security/key_file.h"

namespace shapesense {
namespace fs = std::filesystem;

AuthOptions PrepareDemoAuth(const AuthOptions& given, const fs::path& setup_dir,
                            std::ostream& log) {
  AuthOptions auth = given;
  if (!auth.key_files.empty()) return auth;
  if (auth.insecure) {
    log << "demo: WARNING: --insecure: the demo's programs sign nothing and accept any "
           "target, command and shape (docs/security.md)\n";
    return auth;
  }
  fs::create_directories(setup_dir);
  const fs::path key = setup_dir / "rig.key";
  fs::remove(key);  // the last run's: each run has a key of its own
  WriteKeyFile(key, NewAuthKey(KeyIdFromClock()));
  auth.key_files = {key};
  return auth;
}

std::vector<std::pair<std::string, std::string>> AuthEnvironment(const AuthOptions& auth) {
  if (auth.key_files.empty()) {
    return {{"SHAPESENSE_INSECURE", auth.insecure ? "1" : "0"}, {"SHAPESENSE_KEY_FILES", ""}};
  }
  return {{"SHAPESENSE_KEY_FILES", FormatKeyFiles(auth.key_files)}, {"SHAPESENSE_INSECURE", "0"}};
}

void AddAuthEnvironment(const AuthOptions& auth, ProgramSpec* program) {
  for (auto& variable : AuthEnvironment(auth)) program->environment.push_back(std::move(variable));
}

}  // namespace shapesense
