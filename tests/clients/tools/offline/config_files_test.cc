// The example files in config/ stay true to the code: each parses, and holds
// exactly the documented defaults the code prints.
#include <gtest/gtest.h>

#include "clients/tools/config_command.h"
#include "libs/config/options_yaml.h"
#include "libs/sim/tube_scene.h"
#include "runtime/config_file.h"
#include "runtime/file_io.h"
#include "runtime/sensing_pipeline.h"

namespace shapesense {
namespace {

TEST(ConfigFilesTest, PipelineYamlIsTheDocumentedDefaults) {
  const std::filesystem::path path =
      std::filesystem::path(SHAPESENSE_SOURCE_DIR) / "config" / "pipeline.yaml";
  EXPECT_EQ(ReadTextFile(path), DocumentedDefaults("pipeline"))
      << "regenerate: shapesense config pipeline > config/pipeline.yaml";
  const PipelineOptions loaded = LoadOptionsFile<PipelineOptions>(path);
  YAML::Emitter a, b;
  a << OptionsToYaml(loaded);
  b << OptionsToYaml(PipelineOptions{});
  EXPECT_STREQ(a.c_str(), b.c_str());
}

TEST(ConfigFilesTest, RenderDefaultsRoundTrip) {
  const RenderOptions loaded =
      OptionsFromYamlText<RenderOptions>(DocumentedDefaults("render"), "render");
  YAML::Emitter a, b;
  a << OptionsToYaml(loaded);
  b << OptionsToYaml(RenderOptions{});
  EXPECT_STREQ(a.c_str(), b.c_str());
  EXPECT_EQ(DocumentedDefaults("nonsense"), "");
}

TEST(ConfigFilesTest, ControllerYamlIsWhatTheConfigCommandPrints) {
  const std::filesystem::path path =
      std::filesystem::path(SHAPESENSE_SOURCE_DIR) / "config" / "controller.yaml";
  EXPECT_EQ(ReadTextFile(path), DocumentedDefaults("controller"))
      << "regenerate: shapesense config controller > config/controller.yaml";
}

}  // namespace
}  // namespace shapesense
