#include "clients/tools/demo/demo_auth.h"

#include <chrono>

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
  const auto seconds = std::chrono::duration_cast<std::chrono::seconds>(
      std::chrono::system_clock::now().time_since_epoch());
  WriteKeyFile(key, NewAuthKey(static_cast<uint32_t>(seconds.count())));
  auth.key_files = {key};
  return auth;
}

std::vector<std::pair<std::string, std::string>> AuthEnvironment(const AuthOptions& auth) {
  if (auth.key_files.empty()) {
    return {{"SHAPESENSE_INSECURE", auth.insecure ? "1" : "0"}, {"SHAPESENSE_KEY_FILES", ""}};
  }
  std::string files;
  for (const fs::path& key : auth.key_files) {
    if (!files.empty()) files += ':';
    files += key.string();
  }
  return {{"SHAPESENSE_KEY_FILES", files}, {"SHAPESENSE_INSECURE", "0"}};
}

}  // namespace shapesense
