// Each target of the tree includes only its own headers and those of the
// targets it links, directly or through them. Every include path starts at
// the project root, so the compiler would accept any header of the tree;
// this test holds each target to what its CMakeLists says it uses, from the
// record the build writes (cmake/ShapesenseWarnings.cmake,
// shapesense_record_scope). A header belongs to the target that compiles
// the .cc of the same name; one without a .cc (header-only) to the targets
// of its folder.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace shapesense {
namespace {

namespace fs = std::filesystem;

const fs::path kRoot = SHAPESENSE_SOURCE_DIR;
const fs::path kScopes = fs::path(SHAPESENSE_BINARY_DIR) / "target_scopes.txt";

struct Target {
  std::string folder;
  std::vector<std::string> deps;
  std::vector<std::string> sources;
};

std::vector<std::string> Split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, separator);) {
    if (!part.empty()) parts.push_back(part);
  }
  return parts;
}

std::map<std::string, Target> ReadScopes() {
  std::map<std::string, Target> targets;
  std::ifstream in(kScopes);
  for (std::string line; std::getline(in, line);) {
    // name|folder|deps|sources (the empty fields kept)
    std::vector<std::string> fields;
    std::stringstream parts(line);
    for (std::string field; std::getline(parts, field, '|');) fields.push_back(field);
    if (fields.size() < 2) continue;
    fields.resize(4);
    targets[fields[0]] = {fields[1], Split(fields[2], ','), Split(fields[3], ',')};
  }
  return targets;
}

// The targets `name` may use: itself and what it links, transitively.
std::set<std::string> Closure(const std::map<std::string, Target>& targets,
                              const std::string& name) {
  std::set<std::string> seen;
  std::vector<std::string> to_visit = {name};
  while (!to_visit.empty()) {
    const std::string next = to_visit.back();
    to_visit.pop_back();
    if (!seen.insert(next).second) continue;
    const auto found = targets.find(next);
    if (found == targets.end()) continue;
    for (const std::string& dep : found->second.deps) to_visit.push_back(dep);
  }
  return seen;
}

// "libs/core/error.h" -> "libs/core/error".
std::string Stem(const std::string& path) {
  return (fs::path(path).parent_path() / fs::path(path).stem()).string();
}

// Who may provide each header: the target compiling its .cc, else (a
// header-only file) every target of its folder.
class Owners {
 public:
  explicit Owners(const std::map<std::string, Target>& targets) {
    for (const auto& [name, target] : targets) {
      by_folder_[target.folder].insert(name);
      for (const std::string& source : target.sources) by_stem_[Stem(source)].insert(name);
    }
  }
  // Empty when no target of the tree provides it.
  std::set<std::string> Of(const std::string& header) const {
    if (const auto found = by_stem_.find(Stem(header)); found != by_stem_.end()) {
      return found->second;
    }
    const auto found = by_folder_.find(fs::path(header).parent_path().string());
    return found == by_folder_.end() ? std::set<std::string>{} : found->second;
  }

 private:
  std::map<std::string, std::set<std::string>> by_stem_;
  std::map<std::string, std::set<std::string>> by_folder_;
};

// The project headers a file includes ("libs/...", "runtime/...", ...).
std::vector<std::string> ProjectIncludes(const fs::path& file) {
  std::vector<std::string> includes;
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("#include \"", 0) != 0) continue;
    const std::string target = line.substr(10, line.find('"', 10) - 10);
    for (const char* layer : {"libs/", "runtime/", "services/", "clients/"}) {
      if (target.rfind(layer, 0) == 0) includes.push_back(target);
    }
  }
  return includes;
}

// The files a target answers for: its sources, and the headers of its
// folder that it alone provides (those of its .cc files, and the
// header-only ones when it is its folder's one target).
std::set<std::string> FilesOf(const std::string& name, const Target& target, const Owners& owners) {
  std::set<std::string> files(target.sources.begin(), target.sources.end());
  if (target.folder.empty() || !fs::is_directory(kRoot / target.folder)) return files;
  for (const auto& entry : fs::directory_iterator(kRoot / target.folder)) {
    if (entry.path().extension() != ".h") continue;
    const std::string header = fs::relative(entry.path(), kRoot).string();
    if (owners.Of(header) == std::set<std::string>{name}) files.insert(header);
  }
  return files;
}

TEST(TargetScopeTest, TheBuildRecordedTheTargets) {
  const std::map<std::string, Target> targets = ReadScopes();
  // A record gone missing would make the next test pass on nothing.
  EXPECT_GT(targets.size(), 30u) << kScopes;
  EXPECT_TRUE(targets.count("shapesense_carving")) << kScopes;
  EXPECT_TRUE(targets.count("shapesense-carving")) << kScopes;
}

TEST(TargetScopeTest, EveryTargetIncludesOnlyWhatItLinks) {
  const std::map<std::string, Target> targets = ReadScopes();
  const Owners owners(targets);
  for (const auto& [name, target] : targets) {
    const std::set<std::string> allowed = Closure(targets, name);
    for (const std::string& file : FilesOf(name, target, owners)) {
      for (const std::string& header : ProjectIncludes(kRoot / file)) {
        const std::set<std::string> providers = owners.Of(header);
        bool reachable = providers.empty();  // no target provides it: nothing to link
        for (const std::string& provider : providers) reachable |= allowed.count(provider) > 0;
        std::string by;
        for (const std::string& provider : providers) by += " " + provider;
        EXPECT_TRUE(reachable) << name << ": " << file << " includes " << header << ", provided by"
                               << by << ", which " << name << " does not link";
      }
    }
  }
}

}  // namespace
}  // namespace shapesense
