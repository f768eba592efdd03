#include "libs/control/control_options.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "libs/config/options_yaml.h"
#include "libs/core/error.h"

namespace shapesense {
namespace {

std::string Emitted(const ControllerOptions& options) {
  YAML::Emitter out;
  out << OptionsToYaml(options);
  return out.c_str();
}

TEST(ControllerOptionsTest, TheShippedConfigIsTheDocumentedDefaults) {
  const std::string path = std::string(SHAPESENSE_SOURCE_DIR) + "/config/controller.yaml";
  std::ifstream file(path);
  ASSERT_TRUE(file) << "config/controller.yaml is missing";
  std::stringstream text;
  text << file.rdbuf();
  EXPECT_EQ(text.str(), ControllerDocumentedYaml())
      << "regenerate config/controller.yaml from ControllerDocumentedYaml()";
  const ControllerOptions loaded = ParseControllerYaml(text.str(), "config/controller.yaml");
  EXPECT_EQ(Emitted(loaded), Emitted(ControllerOptions{}));
  EXPECT_EQ(loaded.control_mode(), ControlMode::kClosedLoop);
}

TEST(ControllerOptionsTest, ChangedValuesReadBack) {
  ControllerOptions options;
  options.mode = "model_less";
  options.limits.tendon_ranges = {{-1, 2}, {-2, 3}, {0, 4}};
  options.limits.max_rate = 1.25;
  options.watchdog.hold_age = 0.1;
  options.closed_loop.integral = 0.7;
  options.model_less.damping = 3.5;
  const ControllerOptions back =
      ParseControllerYaml(OptionsToDocumentedYaml(options), "controller.yaml");
  EXPECT_EQ(Emitted(back), Emitted(options));
  EXPECT_EQ(back.control_mode(), ControlMode::kModelLess);
}

void ExpectError(const std::string& text, const std::string& fragment) {
  try {
    ParseControllerYaml(text, "c.yaml");
    ADD_FAILURE() << "accepted: " << text;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos)
        << e.what() << "\n  expected: " << fragment;
  }
}

TEST(ControllerOptionsTest, BadValuesNameTheFileAndTheKey) {
  ExpectError("mode: fast",
              "c.yaml: mode: expected open_loop, closed_loop or model_less, got fast");
  ExpectError("limits: {max_rate: -1}", "c.yaml: limits.max_rate: expected a positive number");
  ExpectError("limits: {min_tension: .nan}", "limits.min_tension: expected a number >= 0");
  ExpectError("limits: {range: {min: 3, max: 1}}", "limits.range.min, max: expected finite");
  ExpectError("limits: {tendon_ranges: [{min: 0, max: 1}, {min: 2, max: 2}]}",
              "limits.tendon_ranges[1].min, max");
  ExpectError("limits: {speed: 1}", "c.yaml: limits.speed: unknown key");
  ExpectError("watchdog: {hold_age: 2, lost_age: 1}",
              "watchdog.lost_age: expected a number of seconds above hold_age (2), got 1");
  ExpectError("workspace: {max_bend_angle: 7}", "workspace.max_bend_angle: expected an angle");
  ExpectError("closed_loop: {integral: -1}", "closed_loop.integral: expected a number >= 0");
  ExpectError("model_less: {broyden_weight: 0}", "model_less.broyden_weight: expected a fraction");
  ExpectError("loop_rate: 0", "loop_rate: expected a rate in [1, 10000], Hz, got 0");
  ExpectError("loop_rate: fast", "loop_rate: expected a number");
}

TEST(ControllerOptionsTest, PerTendonRangesMustMatchTheModel) {
  SafetyLimits limits;
  EXPECT_EQ(limits.ValidateFor(4), "");
  limits.tendon_ranges = {{0, 1}, {0, 2}, {0, 3}};
  EXPECT_EQ(limits.ValidateFor(3), "");
  EXPECT_EQ(limits.RangeOf(2).max, 3.0);
  EXPECT_EQ(limits.ValidateFor(4),
            "tendon_ranges: expected one range per tendon of the model (4), got 3");
}

TEST(ControllerOptionsTest, ModeNamesRoundTrip) {
  for (const ControlMode mode :
       {ControlMode::kOpenLoop, ControlMode::kClosedLoop, ControlMode::kModelLess}) {
    ControlMode parsed = ControlMode::kOpenLoop;
    EXPECT_TRUE(ParseControlMode(ControlModeName(mode), &parsed));
    EXPECT_EQ(parsed, mode);
  }
  ControlMode untouched = ControlMode::kModelLess;
  EXPECT_FALSE(ParseControlMode("closed loop", &untouched));
  EXPECT_EQ(untouched, ControlMode::kModelLess);
}

}  // namespace
}  // namespace shapesense
