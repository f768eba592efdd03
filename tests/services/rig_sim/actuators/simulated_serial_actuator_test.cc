// The simulated serial actuator's side of the protocol (docs/actuators.md),
// line by line without a pty: every command, every error code, the motion
// model and the link watchdog, on its own steady time.
#include "services/rig_sim/actuators/simulated_serial_actuator.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "libs/actuation/line_protocol.h"

namespace shapesense {
namespace {

using ::testing::StartsWith;

class SimulatedSerialActuatorTest : public ::testing::Test {
 protected:
  SimulatedSerialActuatorTest() : actuator_(-1, Options()) {}

  static SimulatedSerialActuatorOptions Options() {
    SimulatedSerialActuatorOptions options;
    options.axes = 3;
    options.max_speed_mm_s = 10.0;
    options.travel_mm = 40.0;
    return options;
  }

  // The reply body to `body` at time `t_s` (the actuator's steady clock, s).
  std::string Ask(const std::string& body, double t_s) {
    std::string line = serial_protocol::EncodeLine(body);
    line.pop_back();
    std::string reply = actuator_.HandleLine(line, kStartUs + static_cast<int64_t>(t_s * 1e6));
    EXPECT_EQ(reply.back(), '\n');
    reply.pop_back();
    const serial_protocol::DecodedLine decoded = serial_protocol::DecodeLine(reply);
    EXPECT_TRUE(decoded.ok()) << decoded.error;
    return decoded.body;
  }

  // The test's time zero on the actuator's steady clock: far after its construction.
  static constexpr int64_t kStartUs = int64_t{1} << 50;
  SimulatedSerialActuator actuator_;
};

TEST_F(SimulatedSerialActuatorTest, AnswersEveryCommand) {
  EXPECT_EQ(Ask("I?", 0), "I 3 shapesense-sim");
  EXPECT_EQ(Ask("T 1 12.5", 0), "T 1 12.5000");
  EXPECT_EQ(Ask("P?", 0), "P 0.0000 0.0000 0.0000");
  EXPECT_EQ(Ask("S?", 0), "S OK");
  EXPECT_EQ(Ask("X", 0), "X");
  EXPECT_EQ(Ask("R", 0), "R");
  EXPECT_EQ(Ask("W 500", 0), "W 500");
  EXPECT_EQ(actuator_.counters().targets, 1);
  EXPECT_EQ(actuator_.counters().stops, 1);
}

TEST_F(SimulatedSerialActuatorTest, ErrorsCarryTheirCodes) {
  EXPECT_THAT(Ask("T 3 1.0", 0), StartsWith("E 3 no axis 3"));
  EXPECT_THAT(Ask("T 0 40.5", 0), StartsWith("E 4 target 40.5 outside"));
  EXPECT_THAT(Ask("T 0 abc", 0), StartsWith("E 2 expected T <axis> <mm>"));
  EXPECT_THAT(Ask("Q", 0), StartsWith("E 2 unknown command 'Q'"));
  EXPECT_THAT(Ask("W -1", 0), StartsWith("E 2"));
  actuator_.InjectFault(7, "motor 2 over temperature");
  EXPECT_EQ(Ask("S?", 0), "S FAULT 7 motor 2 over temperature");
  EXPECT_THAT(Ask("T 0 1.0", 0), StartsWith("E 5 faulted: motor 2 over temperature"));
  EXPECT_EQ(Ask("R", 0), "R");
  EXPECT_EQ(Ask("S?", 0), "S OK");
  EXPECT_EQ(actuator_.counters().refused_targets, 4);
  EXPECT_EQ(actuator_.counters().targets, 0);
}

TEST_F(SimulatedSerialActuatorTest, ADamagedLineIsRefusedAndChangesNothing) {
  std::string line = serial_protocol::EncodeLine("T 0 5.0");
  line.pop_back();
  line[4] = '9';  // "T 0 9.0" with the checksum of "T 0 5.0"
  const std::string reply = actuator_.HandleLine(line, kStartUs);
  EXPECT_THAT(reply, StartsWith("E 1 checksum"));
  EXPECT_TRUE(serial_protocol::DecodeLine(reply.substr(0, reply.size() - 1)).ok());
  EXPECT_EQ(actuator_.targets(), (std::vector<double>{0.0, 0.0, 0.0}));
  EXPECT_EQ(actuator_.counters().checksum_errors, 1);
}

TEST_F(SimulatedSerialActuatorTest, AxesMoveTowardTheirTargetsAtMaxSpeed) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> target(-30.0, 30.0);
  Ask("P?", 0);  // starts the clock
  const std::vector<double> goal = {target(rng), target(rng), target(rng)};
  for (int axis = 0; axis < 3; ++axis) {
    Ask("T " + std::to_string(axis) + " " + serial_protocol::FormatMm(goal[axis]), 0);
  }
  for (const double t : {0.5, 1.0, 2.0, 4.0}) {
    Ask("P?", t);
    const std::vector<double> at = actuator_.positions();
    for (size_t axis = 0; axis < 3; ++axis) {
      const double rounded = std::stod(serial_protocol::FormatMm(goal[axis]));
      const double expected = std::copysign(std::min(std::abs(rounded), 10.0 * t), rounded);
      EXPECT_NEAR(at[axis], expected, 1e-9) << "axis " << axis << " at " << t << " s";
    }
  }
}

TEST_F(SimulatedSerialActuatorTest, TheWatchdogHoldsWhenTheControllerGoesQuiet) {
  Ask("W 200", 0);
  Ask("T 0 20", 0);
  Ask("P?", 0.1);                                       // fed at 0.1 s: still moving
  actuator_.HandleLine("garbage", kStartUs + 250'000);  // no valid line: does not feed it
  const std::string positions = Ask("P?", 0.35);  // 0.25 s after the last valid line: held at 0.3 s
  EXPECT_EQ(actuator_.counters().watchdog_stops, 1);
  EXPECT_NEAR(actuator_.positions()[0], 3.0, 1e-9) << positions;
  EXPECT_EQ(actuator_.targets()[0], actuator_.positions()[0]);
}

}  // namespace
}  // namespace shapesense
