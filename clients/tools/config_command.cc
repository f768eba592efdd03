#include "clients/tools/config_command.h"

#include <iostream>

#include "libs/config/options_yaml.h"
#include "libs/control/control_options.h"
#include "libs/sim/tube_scene.h"
#include "runtime/sensing_pipeline.h"

namespace shapesense {

std::string DocumentedDefaults(const std::string& component) {
  if (component == "pipeline") {
    return "# Options of the sensing chain (shapesense offline --config, the carving and shape\n"
           "# services). Every key is optional; these are the defaults.\n" +
           OptionsToDocumentedYaml(PipelineOptions{});
  }
  if (component == "render") {
    return "# Options of the virtual rig's renderer. Every key is optional; these are the "
           "defaults.\n" +
           OptionsToDocumentedYaml(RenderOptions{});
  }
  if (component == "controller") return ControllerDocumentedYaml();
  return {};
}

void AddConfigCommand(CLI::App& app) {
  auto component = std::make_shared<std::string>();
  CLI::App* command = app.add_subcommand(
      "config", "Print a component's options with their documentation and defaults");
  command->add_option("component", *component, "pipeline | render | controller")->required();
  command->callback([component] {
    const std::string text = DocumentedDefaults(*component);
    if (text.empty())
      throw CLI::ValidationError("component",
                                 "unknown: " + *component + " (pipeline | render | controller)");
    std::cout << text;
  });
}

}  // namespace shapesense
