#pragma once

#include <filesystem>
#include <string>

#include "libs/config/options_yaml.h"
#include "runtime/file_io.h"

namespace shapesense {

// Loads an options struct from a YAML file, validated once; errors name the
// file and key. An empty path gives the documented defaults.
template <class Options>
Options LoadOptionsFile(const std::filesystem::path& path) {
  if (path.empty()) return OptionsFromYaml<Options>(YAML::Node(), "(defaults)");
  return OptionsFromYamlText<Options>(ReadTextFile(path), path.string());
}

// A path from a config file: relative ones are relative to the config's
// folder (every config of the project follows this rule).
inline std::filesystem::path ResolveConfigPath(const std::filesystem::path& config_file,
                                               const std::string& value) {
  const std::filesystem::path path(value);
  if (path.empty() || path.is_absolute() || config_file.empty()) return path;
  return config_file.parent_path() / path;
}

}  // namespace shapesense
