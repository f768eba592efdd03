#include "runtime/lcm/service_config.h"

#include "libs/core/error.h"
#include "runtime/file_io.h"

namespace shapesense {

YAML::Node ReadServiceConfig(const std::filesystem::path& config,
                             const ServiceOverrides& overrides) {
  YAML::Node node;
  if (!config.empty()) {
    try {
      node = YAML::Load(ReadTextFile(config));
    } catch (const YAML::Exception& e) {
      throw InputError(config.string() + ": not valid YAML: " + e.what());
    }
  }
  if (!node || node.IsNull()) node = YAML::Node(YAML::NodeType::Map);
  if (!node.IsMap()) throw InputError(config.string() + ": (top level): expected a map");
  if (!overrides.rig.empty()) node["rig"] = std::filesystem::absolute(overrides.rig).string();
  if (!overrides.backgrounds.empty()) {
    node["backgrounds"] = std::filesystem::absolute(overrides.backgrounds).string();
  }
  if (overrides.lcm_url) node["lcm_url"] = *overrides.lcm_url;
  return node;
}

}  // namespace shapesense
