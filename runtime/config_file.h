#pragma once

#include <filesystem>

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

}  // namespace shapesense
