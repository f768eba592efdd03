// Actuator options: the shipped config/actuators.yaml loads and validates,
// defaults are valid and survive their documented YAML, every bad value names
// its key, and the factory builds the driver the config names without
// opening anything.
#include "services/controller/actuators/actuator_options.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <functional>

#include "libs/config/options_yaml.h"
#include "libs/core/error.h"
#include "runtime/config_file.h"
#include "services/controller/actuators/actuator_factory.h"
#include "services/controller/actuators/canopen_driver.h"
#include "services/controller/actuators/serial_driver.h"

namespace shapesense {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

const std::string kConfigPath = std::string(SHAPESENSE_SOURCE_DIR) + "/config/actuators.yaml";

TEST(ActuatorOptionsTest, TheShippedConfigLoadsAndHoldsTheDefaults) {
  const ActuatorOptions loaded = LoadOptionsFile<ActuatorOptions>(kConfigPath);
  const ActuatorOptions defaults;
  // The file documents the defaults: every key as the struct has it.
  EXPECT_EQ(YAML::Dump(OptionsToYaml(loaded)), YAML::Dump(OptionsToYaml(defaults)));
}

TEST(ActuatorOptionsTest, DocumentedYamlReadsBackToTheSameOptions) {
  ActuatorOptions options;
  options.driver = "socketcan";
  options.tendons = 2;
  options.canopen.node_ids = {5, 9};
  options.canopen.counts_per_mm = -512.5;
  options.serial.reply_timeout_s = 0.3;
  const std::string text = OptionsToDocumentedYaml(options);
  EXPECT_THAT(text, HasSubstr("# serial | socketcan | simulated"));
  const ActuatorOptions read = OptionsFromYamlText<ActuatorOptions>(text, "test");
  EXPECT_EQ(YAML::Dump(OptionsToYaml(read)), YAML::Dump(OptionsToYaml(options)));
}

TEST(ActuatorOptionsTest, EveryBadValueNamesItsKey) {
  const std::vector<std::pair<std::function<void(ActuatorOptions&)>, std::string>> cases = {
      {[](ActuatorOptions& o) { o.driver = "ethercat"; },
       "driver: expected serial, socketcan, simulated or rig, got 'ethercat'"},
      {[](ActuatorOptions& o) { o.tendons = 0; }, "tendons: expected 1-32, got 0"},
      {[](ActuatorOptions& o) { o.serial.device = ""; }, "serial.device: "},
      {[](ActuatorOptions& o) { o.serial.baud = 12345; }, "serial.baud: "},
      {[](ActuatorOptions& o) { o.serial.reply_timeout_s = 0.0; }, "serial.reply_timeout_s: "},
      {[](ActuatorOptions& o) { o.serial.retries = -1; }, "serial.retries: "},
      {[](ActuatorOptions& o) { o.serial.device_watchdog_s = 0.001; },
       "serial.device_watchdog_s: expected 0 (off) or 0.01-60 s"},
      {[](ActuatorOptions& o) { o.canopen.interface = ""; }, "canopen.interface: "},
      {[](ActuatorOptions& o) {
         o.canopen.node_ids = {1, 128};
       },
       "canopen.node_ids[1]: expected a node id 1-127, got 128"},
      {[](ActuatorOptions& o) {
         o.canopen.node_ids = {3, 3};
       },
       "canopen.node_ids[1]: expected a node id no other drive has"},
      {[](ActuatorOptions& o) { o.canopen.counts_per_mm = 0.0; }, "canopen.counts_per_mm: "},
      {[](ActuatorOptions& o) { o.canopen.profile_velocity_mm_s = 1e12; },
       "canopen.profile_velocity_mm_s: expected a positive number whose counts fit 32 bits"},
      {[](ActuatorOptions& o) { o.canopen.heartbeat_timeout_s = 0.05; },
       "canopen.heartbeat_timeout_s: expected more than heartbeat_period_s"},
      {[](ActuatorOptions& o) { o.canopen.pdo_retries = 11; }, "canopen.pdo_retries: "},
      {[](ActuatorOptions& o) { o.simulated.time_constant_s = -1.0; },
       "simulated.time_constant_s: "},
      {[](ActuatorOptions& o) { o.rig.state_timeout_s = 0.0; }, "rig.state_timeout_s: "},
      {[](ActuatorOptions& o) { o.rig.connect_timeout_s = 100.0; }, "rig.connect_timeout_s: "},
      {[](ActuatorOptions& o) {
         o.driver = "socketcan";
         o.tendons = 3;
       },
       "canopen.node_ids: expected one node id per tendon (3), got 4 ids"},
  };
  EXPECT_EQ(ActuatorOptions{}.Validate(), "");
  for (const auto& [change, expected] : cases) {
    ActuatorOptions options;
    change(options);
    EXPECT_THAT(options.Validate(), StartsWith(expected));
  }
}

TEST(ActuatorOptionsTest, FileErrorsNameTheFileAndKey) {
  try {
    OptionsFromYamlText<ActuatorOptions>("driver: serial\nserial: {baud: fast}\n", "act.yaml");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "act.yaml: serial.baud: expected an integer");
  }
  try {
    OptionsFromYamlText<ActuatorOptions>("canopen: {nodes: [1]}\n", "act.yaml");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "act.yaml: canopen.nodes: unknown key");
  }
}

TEST(ActuatorFactoryTest, BuildsTheNamedDriverWithoutOpeningIt) {
  ActuatorOptions options;
  options.driver = "serial";
  options.serial.device = "/dev/shapesense-no-such-port";
  std::unique_ptr<ActuatorDriver> serial = MakeActuatorDriver(options);
  EXPECT_NE(dynamic_cast<SerialActuatorDriver*>(serial.get()), nullptr);
  EXPECT_EQ(serial->description(), "serial /dev/shapesense-no-such-port");
  EXPECT_EQ(serial->Status().state, ActuatorState::kDisconnected);
  EXPECT_THROW(serial->CommandTargets(std::vector<double>(4, 0.0)), ActuatorError);

  options.driver = "socketcan";
  options.canopen.interface = "can7";
  std::unique_ptr<ActuatorDriver> can = MakeActuatorDriver(options);
  EXPECT_NE(dynamic_cast<CanOpenActuatorDriver*>(can.get()), nullptr);
  EXPECT_EQ(can->description(), "socketcan can7");
  EXPECT_EQ(can->axis_count(), 4);

  options.driver = "simulated";
  int plant_calls = 0;
  std::unique_ptr<ActuatorDriver> simulated =
      MakeActuatorDriver(options, {[&](std::span<const double> mm, int64_t) {
                                     ++plant_calls;
                                     EXPECT_EQ(mm.size(), 4u);
                                   },
                                   {}});
  EXPECT_NE(dynamic_cast<SimulatedActuatorDriver*>(simulated.get()), nullptr);
  simulated->Connect();
  EXPECT_GT(plant_calls, 0);

  options.driver = "rig";  // needs LCM: the controller service makes it
  EXPECT_THROW(MakeActuatorDriver(options), std::invalid_argument);

  options.driver = "simulated";
  options.tendons = 0;
  EXPECT_THROW(MakeActuatorDriver(options), std::invalid_argument);
}

TEST(ActuatorFactoryTest, AMissingSerialPortIsAClearConnectError) {
  ActuatorOptions options;
  options.driver = "serial";
  options.serial.device = "/dev/shapesense-no-such-port";
  options.serial.connect_timeout_s = 0.0;
  std::unique_ptr<ActuatorDriver> driver = MakeActuatorDriver(options);
  try {
    driver->Connect();
    FAIL() << "expected ActuatorError";
  } catch (const ActuatorError& e) {
    EXPECT_THAT(e.what(), HasSubstr("serial /dev/shapesense-no-such-port: cannot connect: "
                                    "/dev/shapesense-no-such-port: cannot open: No such file"));
  }
  EXPECT_EQ(driver->Status().state, ActuatorState::kDisconnected);
  EXPECT_FALSE(driver->Health().link_alive);
}

}  // namespace
}  // namespace shapesense
