// The layers of docs/architecture.md, checked on every source file:
// libs → runtime → services → clients, with no arrow upward; no service
// reaching into another service's folder (what they share lives lower); and
// libs free of LCM and its message types (runtime/lcm adapts those). A file
// that breaks a rule fails the test with the line that does.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace shapesense {
namespace {

namespace fs = std::filesystem;

const fs::path kRoot = SHAPESENSE_SOURCE_DIR;

// The layer of a path relative to the root ("libs/core/error.h"), from
// lowest to highest; nullopt for what is not a layer (messages, tests).
std::optional<int> LayerOf(const std::string& path) {
  static const std::map<std::string, int> kLayers = {
      {"libs", 0}, {"runtime", 1}, {"services", 2}, {"clients", 3}};
  const auto slash = path.find('/');
  if (slash == std::string::npos) return std::nullopt;
  const auto found = kLayers.find(path.substr(0, slash));
  if (found == kLayers.end()) return std::nullopt;
  return found->second;
}

// "services/capture/x.h" -> "capture"; "" when not under services/.
std::string ServiceOf(const std::string& path) {
  const std::string prefix = "services/";
  if (path.rfind(prefix, 0) != 0) return "";
  return path.substr(prefix.size(), path.find('/', prefix.size()) - prefix.size());
}

struct Include {
  std::string file;  // relative to the root
  int line = 0;
  std::string target;  // what is included, as written
  bool quoted = false;
};

std::vector<Include> IncludesUnder(const std::string& folder) {
  std::vector<Include> includes;
  for (const auto& entry : fs::recursive_directory_iterator(kRoot / folder)) {
    const std::string extension = entry.path().extension().string();
    if (!entry.is_regular_file() || (extension != ".h" && extension != ".cc")) continue;
    std::ifstream in(entry.path());
    std::string text;
    for (int line = 1; std::getline(in, text); ++line) {
      if (text.rfind("#include ", 0) != 0) continue;
      const char open = text[9];
      const auto close = text.find(open == '"' ? '"' : '>', 10);
      if (close == std::string::npos) continue;
      includes.push_back({fs::relative(entry.path(), kRoot).string(), line,
                          text.substr(10, close - 10), open == '"'});
    }
  }
  return includes;
}

std::string Where(const Include& include) {
  return include.file + ":" + std::to_string(include.line) + ": " + include.target;
}

std::vector<Include> AllIncludes() {
  std::vector<Include> all;
  for (const char* folder : {"libs", "runtime", "services", "clients"}) {
    for (Include& include : IncludesUnder(folder)) all.push_back(std::move(include));
  }
  return all;
}

TEST(LayeringTest, TheTreeHasSourcesToCheck) {
  // A moved root would make every other test here pass on nothing.
  EXPECT_GT(AllIncludes().size(), 1000u);
}

TEST(LayeringTest, NoLayerIncludesAHigherOne) {
  for (const Include& include : AllIncludes()) {
    if (!include.quoted) continue;
    const std::optional<int> from = LayerOf(include.file);
    const std::optional<int> to = LayerOf(include.target);
    if (from && to) {
      EXPECT_LE(*to, *from) << Where(include);
    }
  }
}

TEST(LayeringTest, NoServiceIncludesAnotherServicesFolder) {
  for (const Include& include : AllIncludes()) {
    const std::string from = ServiceOf(include.file);
    const std::string to = ServiceOf(include.target);
    if (!from.empty() && !to.empty()) {
      EXPECT_EQ(from, to) << Where(include);
    }
  }
}

TEST(LayeringTest, LibrariesUseNeitherLcmNorItsMessages) {
  for (const Include& include : IncludesUnder("libs")) {
    EXPECT_NE(include.target.rfind("shapesense/", 0), 0u) << Where(include);
    EXPECT_NE(include.target.rfind("lcm/", 0), 0u) << Where(include);
  }
}

}  // namespace
}  // namespace shapesense
