// The controller service's config: the shipped example loads with its
// trajectory resolved; every bad file or value names the config, the key
// and what is wrong; and nothing is opened before all of it is checked.
#include "services/controller/controller_config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "libs/config/options_yaml.h"
#include "libs/core/error.h"
#include "services/controller/controller_command.h"
#include "tests/services/controller/in_process_rig.h"

namespace shapesense {
namespace {
namespace fs = std::filesystem;

using ::testing::HasSubstr;
using ::testing::StartsWith;

const fs::path kConfigDir = fs::path(SHAPESENSE_SOURCE_DIR) / "config";

void Write(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

// A client config in `dir` naming the shipped files by absolute path, with `extra` appended.
fs::path ClientConfig(const fs::path& dir, const std::string& extra) {
  fs::path path = dir / "client.yaml";
  Write(path, "controller: " + (kConfigDir / "controller.yaml").string() +
                  "\nactuators: " + (kConfigDir / "actuators.yaml").string() +
                  "\nmanipulator: " + (kConfigDir / "manipulator.yaml").string() + "\n" + extra);
  return path;
}

std::string LoadError(const fs::path& config) {
  try {
    LoadControllerSetup(config);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(loaded)";
}

TEST(ControllerConfigTest, TheShippedConfigLoadsWithItsTrajectory) {
  const ControllerSetup setup = LoadControllerSetup(kConfigDir / "controller_client.yaml");
  EXPECT_EQ(setup.actuators.driver, "rig");
  EXPECT_EQ(setup.actuators.tendons, 4);
  EXPECT_EQ(setup.controller.mode, "closed_loop");
  EXPECT_FALSE(setup.client.stream_targets());
  ASSERT_EQ(setup.trajectory.targets.size(), 8u);
  EXPECT_TRUE(setup.trajectory.interpolate);
  EXPECT_DOUBLE_EQ(setup.trajectory.targets.back().time, 35.0);
  // Relative paths are the config folder's.
  EXPECT_EQ(fs::path(setup.client.targets), kConfigDir / "targets.yaml");
  EXPECT_EQ(fs::path(setup.client.log.csv), kConfigDir / "../controller-output/controller_log.csv");
  // The tip target resolves to a configuration whose tip is where it was asked.
  EXPECT_LT(setup.trajectory.targets[5].tip_residual, 0.05);
}

TEST(ControllerConfigTest, DefaultsSurviveTheirDocumentedYaml) {
  ControllerClientOptions options;
  options.targets = "stream";
  options.driver = "simulated";
  options.log.flush_period_s = 0.25;
  const ControllerClientOptions read =
      OptionsFromYamlText<ControllerClientOptions>(OptionsToDocumentedYaml(options), "test");
  EXPECT_EQ(YAML::Dump(OptionsToYaml(read)), YAML::Dump(OptionsToYaml(options)));
  EXPECT_EQ(ControllerClientOptions{}.Validate(), "");
}

TEST(ControllerConfigTest, EveryErrorNamesTheConfigTheKeyAndWhat) {
  const fs::path dir = testing::TestLogDir();
  const std::string config = (dir / "client.yaml").string();
  const fs::path csv = dir / "t.csv";
  Write(csv, "time,kappa_x,kappa_z,eps0,eps1\n0,0,0,0,0.002\n1,0.001,0,0\n");
  const fs::path far = dir / "far.yaml";
  Write(far,
        "targets:\n  - {time: 0, q: [0, 0, 0, 0.002]}\n  - {time: 1, q: [0.03, 0, 0, 0.002]}\n");
  const fs::path three = dir / "three.yaml";
  Write(three, "tendons: 3\n");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"targets: stream\nbogus: 1\n", config + ": bogus: unknown key"},
      {"targets: stream\nduration_s: -1\n", config + ": duration_s: expected 0 (until stopped)"},
      {"targets: stream\nlog: {flush_period_s: 0}\n", config + ": log.flush_period_s: expected"},
      {"targets: " + csv.string() + "\n",
       config + ": targets: " + csv.string() + ": line 3: expected 5 columns, got 4"},
      {"targets: " + far.string() + "\n",
       config + ": targets: " + far.string() + ": targets[1]: curvature 0.03 /mm beyond"},
      {"targets: " + (dir / "missing.yaml").string() + "\n",
       config + ": targets: " + (dir / "missing.yaml").string()},
      {"targets: stream\ndriver: ethercat\n",
       config + ": driver: driver: expected serial, socketcan, simulated or rig"},
      {"targets: stream\nactuators: " + three.string() + "\n",
       config + ": actuators: tendons: expected 4 (the manipulator's tendons), got 3"},
  };
  for (const auto& [extra, expected] : cases) {
    // The shipped files, then the case's keys (a later key overrides an earlier one).
    std::string text = extra;
    if (extra.find("actuators:") == std::string::npos) {
      text = "actuators: " + (kConfigDir / "actuators.yaml").string() + "\n" + extra;
    }
    Write(config, "controller: " + (kConfigDir / "controller.yaml").string() +
                      "\nmanipulator: " + (kConfigDir / "manipulator.yaml").string() + "\n" + text);
    EXPECT_THAT(LoadError(config), StartsWith(expected)) << extra;
  }
}

TEST(ControllerConfigTest, NothingIsOpenedBeforeEverythingIsChecked) {
  // A serial port that does not exist and a target out of reach: the
  // target is the error, the port was never tried and no log was created.
  const fs::path dir = testing::TestLogDir();
  const fs::path far = dir / "far.yaml";
  Write(far, "targets:\n  - {time: 0, q: [0.03, 0, 0, 0.002]}\n");
  const fs::path config = ClientConfig(dir, "driver: serial\ntargets: " + far.string() +
                                                "\nlog: {csv: out/log.csv, lcm: out/log.lcmlog}\n");
  const std::string config_arg = config.string();
  std::vector<std::string> args = {"shapesense-controller", "--config", config_arg};
  std::vector<char*> argv;
  argv.reserve(args.size());
  for (std::string& arg : args) argv.push_back(arg.data());
  std::ostringstream captured;
  std::streambuf* saved = std::cerr.rdbuf(captured.rdbuf());
  const int code = ControllerMain(static_cast<int>(argv.size()), argv.data());
  std::cerr.rdbuf(saved);
  EXPECT_EQ(code, 2);
  EXPECT_THAT(captured.str(), HasSubstr("shapesense-controller: error: " + config_arg +
                                        ": targets: " + far.string() + ": targets[0]: curvature"));
  EXPECT_THAT(captured.str(), ::testing::Not(HasSubstr("ttyUSB")));
  EXPECT_FALSE(fs::exists(dir / "out"));
}

}  // namespace
}  // namespace shapesense
