// `shapesense replay` with the shape config's configuration section on: the
// replayed shapes carry q (in the shape log and the JSON lines), close to
// the configuration the recorded images were rendered from; a model file
// that is missing is refused before any output is written.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "clients/tools/replay/replay_command.h"
#include "libs/config/options_yaml.h"
#include "libs/core/error.h"
#include "libs/mechanics/manipulator_options.h"
#include "libs/sim/manipulator_scene.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/shape_message.h"
#include "tests/support/service_test_options.h"
#include "tests/support/test_rig.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;

constexpr SectionLengths kRest{60.0, 140.0};

class ReplayConfigurationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("replay_configuration_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    rig_.WriteFiles(dir_ / "rig");
    CarvingServiceOptions carving = testing::TestCarvingOptions();
    carving.rig = "rig/rig.yaml";
    carving.backgrounds = "rig/background";
    WriteFileAtomically(dir_ / "carving.yaml", OptionsToDocumentedYaml(carving));
    ShapeServiceOptions shape = testing::TestShapeOptions();
    shape.rig = carving.rig;
    shape.configuration.enabled = true;
    shape.configuration.manipulator = "arm.yaml";
    const Vec3 base = rig_.rig().base_point;
    shape.configuration.base.base_position = {base.x(), base.y(), base.z()};
    shape.configuration.base.base_rotation = {std::numbers::pi / 2.0, 0.0, 0.0};
    WriteFileAtomically(dir_ / "shape.yaml", OptionsToDocumentedYaml(shape));
    world_from_base_ = shape.configuration.base.WorldFromBase();
    ManipulatorOptions model = ParseManipulatorYaml(
        ReadTextFile(fs::path(SHAPESENSE_SOURCE_DIR) / "config" / "manipulator.yaml"), "model");
    model.proximal_length = kRest.proximal;
    model.distal_length = kRest.distal;
    WriteFileAtomically(dir_ / "arm.yaml", FormatManipulatorYaml(model));
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Records the images of each configuration as frame-set 20, 21, ...
  void Record(const std::vector<Configuration>& configurations) {
    const SceneRenderer renderer(rig_.rig());
    lcm::LogFile log((dir_ / "images.lcmlog").string(), "w");
    int64_t time = 1'000'000;
    for (size_t i = 0; i < configurations.size(); ++i) {
      const TubeScene scene = SceneOfConfiguration(configurations[i], kRest, world_from_base_, {});
      const std::vector<RenderedView> views =
          renderer.Render(scene, RenderOptions{}, static_cast<uint32_t>(i));
      for (size_t k = 0; k < views.size(); ++k) {
        const int64_t seq = 20 + static_cast<int64_t>(i);
        std::vector<uint8_t> bytes = testing::Encode(
            testing::MakeImageMessage(views[k].image, rig_.rig().cameras[k].name, seq, time));
        lcm::LogEvent event{};
        event.timestamp = time + static_cast<int64_t>(k) * 100;
        event.channel = channels::Image(rig_.rig().cameras[k].name);
        event.datalen = static_cast<int32_t>(bytes.size());
        event.data = bytes.data();
        ASSERT_EQ(log.writeEvent(&event), 0);
      }
      time += 100'000;
    }
  }

  ReplayArgs Args() const {
    ReplayArgs args;
    args.logs = {dir_ / "images.lcmlog"};
    args.config = dir_ / "carving.yaml";
    args.shape_config = dir_ / "shape.yaml";
    args.out = dir_ / "out" / "shapes.jsonl";
    args.progress = false;
    return args;
  }

  testing::TestRig rig_{7};
  Pose3 world_from_base_ = Pose3::Identity();
  fs::path dir_;
};

TEST_F(ReplayConfigurationTest, ReplayedShapesCarryQ) {
  const std::vector<Configuration> configurations = {Configuration(0.006, 0.003, 0.01, 0.02),
                                                     Configuration(-0.002, -0.009, 0.02, 0.0)};
  Record(configurations);
  std::map<int64_t, shape_t> replayed;
  std::ostringstream log;
  const ReplaySummary summary =
      RunReplay(Args(), log, [&](const shape_t& s) { replayed[s.trigger_seq] = s; });
  EXPECT_EQ(summary.measured, 2);
  ASSERT_EQ(replayed.size(), 2u);
  for (size_t i = 0; i < configurations.size(); ++i) {
    const shape_t& shape = replayed.at(20 + static_cast<int64_t>(i));
    ASSERT_TRUE(shape.has_configuration);
    const Configuration& q = configurations[i];
    const Configuration sensed = *MessageConfiguration(shape);
    EXPECT_LT((sensed.head<2>() - q.head<2>()).norm(), 0.01 * q.head<2>().norm());
    EXPECT_NEAR(sensed(3), q(3), 3e-3);
  }
  std::ifstream json(Args().out);
  std::string line;
  int with_q = 0;
  while (std::getline(json, line)) {
    const nlohmann::json parsed = nlohmann::json::parse(line);
    ASSERT_TRUE(parsed.contains("q")) << line.substr(0, 200);
    const shape_t& shape = replayed.at(parsed.at("trigger_seq").get<int64_t>());
    for (size_t c = 0; c < 4; ++c) EXPECT_EQ(parsed["q"][c].get<double>(), shape.q[c]);
    ++with_q;
  }
  EXPECT_EQ(with_q, 2);
}

TEST_F(ReplayConfigurationTest, AMissingModelFileIsRefusedBeforeAnyOutput) {
  Record({Configuration(0.006, 0.003, 0.01, 0.02)});
  fs::remove(dir_ / "arm.yaml");
  std::ostringstream log;
  try {
    RunReplay(Args(), log);
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("arm.yaml"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(Args().out));
}

}  // namespace
}  // namespace shapesense
