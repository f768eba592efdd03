#include "runtime/rig/rig_file.h"

#include <yaml-cpp/yaml.h>

#include "libs/core/error.h"

namespace shapesense {
namespace {

struct Reader {
  std::string source;

  [[noreturn]] void Fail(const std::string& key, const std::string& what) const {
    throw InputError(DescribeInputError(source, key, what));
  }

  template <class T>
  T Get(const YAML::Node& node, const std::string& key, const std::string& path, T fallback) const {
    const YAML::Node value = node[key];
    if (!value || value.IsNull()) return fallback;
    try {
      return value.as<T>();
    } catch (const YAML::Exception&) {
      Fail(path + key, "expected " + Kind<T>() + ", got '" + YAML::Dump(value) + "'");
    }
  }

  template <class T>
  static std::string Kind() {
    if constexpr (std::is_same_v<T, std::string>) return "text";
    if constexpr (std::is_same_v<T, int>) return "an integer";
    if constexpr (std::is_same_v<T, double>) return "a number";
    return "a list";
  }
};

RigProgram ParseProgram(const Reader& reader, const YAML::Node& node, const std::string& path) {
  if (!node.IsMap()) reader.Fail(path, "expected a map with `program`");
  RigProgram program;
  program.program = reader.Get<std::string>(node, "program", path, "");
  if (program.program.empty()) reader.Fail(path + "program", "missing");
  program.config = reader.Get<std::string>(node, "config", path, "");
  program.args = reader.Get<std::vector<std::string>>(node, "args", path, {});
  program.cpus = reader.Get<std::vector<int>>(node, "cpus", path, {});
  program.realtime_priority = reader.Get<int>(node, "realtime_priority", path, 0);
  return program;
}

RigHost ParseHost(const Reader& reader, const std::string& name, const YAML::Node& node) {
  const std::string path = "hosts." + name + ".";
  if (!node.IsMap()) reader.Fail("hosts." + name, "expected a map with interface and programs");
  RigHost host;
  host.name = name;
  host.interface = reader.Get<std::string>(node, "interface", path, "");
  host.keys = reader.Get<std::vector<std::string>>(node, "keys", path, {});
  const YAML::Node programs = node["programs"];
  if (programs && !programs.IsSequence()) reader.Fail(path + "programs", "expected a list");
  for (size_t i = 0; programs && i < programs.size(); ++i) {
    host.programs.push_back(
        ParseProgram(reader, programs[i], path + "programs[" + std::to_string(i) + "]."));
  }
  return host;
}

std::vector<ChannelRoute> ParseChannels(const Reader& reader, const YAML::Node& node) {
  std::vector<ChannelRoute> routes;
  if (!node || node.IsNull()) return routes;
  if (!node.IsMap()) reader.Fail("rig.channels", "expected a map CHANNEL: rig|local");
  for (const auto& item : node) {
    const std::string channel = item.first.as<std::string>();
    const std::string network = item.second.as<std::string>();
    try {
      std::string route = channel;
      route += '=';
      route += network;
      const std::vector<ChannelRoute> parsed = ChannelNetworks::Parse(route);
      routes.insert(routes.end(), parsed.begin(), parsed.end());
    } catch (const std::invalid_argument& error) {
      reader.Fail("rig.channels." + channel, error.what());
    }
  }
  return routes;
}

}  // namespace

RigFile ParseRigFile(const std::string& text, const std::filesystem::path& source) {
  const Reader reader{source.string()};
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(source.string() + ": not valid YAML: " + e.what());
  }
  if (!root.IsMap() || !root["rig"] || !root["rig"].IsMap()) reader.Fail("rig", "missing");
  const YAML::Node rig = root["rig"];
  RigFile file;
  file.path = source;
  file.name = reader.Get<std::string>(rig, "name", "rig.", "");
  file.prefix = reader.Get<std::string>(rig, "prefix", "rig.", "");
  file.rig_network = reader.Get<std::string>(rig, "rig_network", "rig.", "");
  file.local_network = reader.Get<std::string>(rig, "local_network", "rig.", "");
  file.clock_offset_warning_ms = reader.Get<double>(rig, "clock_offset_warning_ms", "rig.", 1.0);
  file.insecure = reader.Get<bool>(rig, "insecure", "rig.", false);
  file.cameras = reader.Get<std::vector<std::string>>(rig, "cameras", "rig.", {});
  file.channels = ParseChannels(reader, rig["channels"]);
  const YAML::Node hosts = root["hosts"];
  if (!hosts || !hosts.IsMap()) reader.Fail("hosts", "expected a map of hosts");
  for (const auto& item : hosts) {
    file.hosts.push_back(ParseHost(reader, item.first.as<std::string>(), item.second));
  }
  return file;
}

}  // namespace shapesense
