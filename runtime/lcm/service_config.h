#pragma once

// Loading a service's config: the YAML file, the command line's overrides,
// validation once, paths relative to the config file.
#include <filesystem>
#include <optional>
#include <string>

#include "libs/config/options_yaml.h"
#include "runtime/lcm/pipeline_stages.h"

namespace shapesense {

// What a service's command line may override in its config.
struct ServiceOverrides {
  std::filesystem::path rig;
  std::filesystem::path backgrounds;
  std::optional<std::string> lcm_url;
};

// The config file's YAML map (an empty map without a file) with the
// overrides written in (paths made absolute). InputError naming the file on
// unreadable or non-map YAML.
YAML::Node ReadServiceConfig(const std::filesystem::path& config,
                             const ServiceOverrides& overrides);

// Options with `rig` and `lcm_url` keys, and maybe `backgrounds`, read and
// validated (InputError naming the file and key), their paths resolved
// against the config file's folder.
template <class Options>
Options LoadServiceOptions(const std::filesystem::path& config, const ServiceOverrides& overrides) {
  const std::string source = config.empty() ? "(command line)" : config.string();
  Options options = OptionsFromYaml<Options>(ReadServiceConfig(config, overrides), source);
  options.rig = ResolveConfigPath(config, options.rig).string();
  if constexpr (requires { options.backgrounds; }) {
    options.backgrounds = ResolveConfigPath(config, options.backgrounds).string();
  }
  return options;
}

}  // namespace shapesense
