// The virtual rig's plant driver over LCM memq://, on a simulated clock,
// against the fake plant peer: it connects only when the plant answers,
// carries targets to the plant, reports the plant's positions, stops, loses
// the link when the plant falls silent, and reports the plant's faults.
// Also the wire checks of the tendon messages it decodes.
#include "services/controller/rig_plant_driver.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "runtime/lcm/channels.h"
#include "runtime/lcm/wire_check.h"
#include "shapesense/tendon_state_t.hpp"
#include "tests/services/controller/fake_rig_plant.h"
#include "tests/services/controller/in_process_rig.h"

namespace shapesense {
namespace {

using ::testing::HasSubstr;

class RigPlantDriverTest : public ::testing::Test {
 protected:
  RigPlantDriverTest()
      : plant_(
            bus_, testing::CatheterModel(), testing::FakeRigOptions{}, [this] { return now_; },
            Eigen::VectorXd::Constant(4, 0.5)),
        driver_(bus_, 4, Options(), [this] { return now_; }) {}

  static RigActuatorOptions Options() {
    RigActuatorOptions options;
    options.state_timeout_s = 0.2;
    options.connect_timeout_s = 0.05;
    return options;
  }
  // `seconds` of 10 ms ticks of the plant, every message handled.
  void Run(double seconds) {
    for (int i = 0; i < static_cast<int>(std::lround(seconds * 100.0)); ++i) {
      now_ += 10'000;
      plant_.Tick();
      while (bus_.Handle(0) > 0) {
      }
    }
  }

  int64_t now_ = 1'700'000'000'000'000;
  LcmBus bus_{"memq://"};
  testing::FakeRigPlant plant_;
  RigPlantDriver driver_;
};

TEST_F(RigPlantDriverTest, ConnectsOnlyWhenThePlantAnswers) {
  EXPECT_EQ(driver_.Status().state, ActuatorState::kDisconnected);
  EXPECT_THROW(driver_.CommandTargets(std::vector<double>(4, 1.0)), ActuatorError);
  try {
    driver_.Connect();  // nothing published yet
    FAIL() << "expected ActuatorError";
  } catch (const ActuatorError& e) {
    EXPECT_THAT(e.what(),
                HasSubstr("rig: cannot connect: no plant state on SHAPESENSE_PLANT_STATE"));
  }
  plant_.Tick();
  driver_.Connect();
  EXPECT_TRUE(driver_.Status().ok());
  EXPECT_EQ(driver_.ReadPositions().mm, std::vector<double>(4, 0.5));
  EXPECT_EQ(driver_.Health().connects, 1);
}

TEST_F(RigPlantDriverTest, CarriesTargetsToThePlantAndStops) {
  plant_.Tick();
  driver_.Connect();
  const std::vector<double> targets = {1.0, 1.5, 2.0, 0.25};
  driver_.CommandTargets(targets);
  Run(0.02);
  EXPECT_EQ(plant_.moves(), 1);
  EXPECT_EQ(driver_.ReadPositions().mm, targets);
  driver_.Stop();
  Run(0.02);
  EXPECT_EQ(plant_.stops(), 1);
  EXPECT_EQ(plant_.moves(), 1);
  EXPECT_TRUE(driver_.Status().ok()) << "a stop keeps the link";
  EXPECT_THROW(driver_.CommandTargets(std::vector<double>(3, 1.0)), ActuatorError);
  EXPECT_THROW(driver_.CommandTargets(std::vector<double>(4, std::nan(""))), ActuatorError);
}

TEST_F(RigPlantDriverTest, APlantThatFallsSilentIsALostLink) {
  plant_.Tick();
  driver_.Connect();
  Run(0.5);
  EXPECT_TRUE(driver_.Status().ok());
  plant_.set_answering(false);
  Run(0.2);
  EXPECT_TRUE(driver_.Status().ok()) << "0.2 s silent is still within state_timeout_s";
  Run(0.02);
  const ActuatorStatus status = driver_.Status();
  EXPECT_EQ(status.state, ActuatorState::kDisconnected);
  EXPECT_THAT(status.reason, HasSubstr("rig: link lost: no plant state on SHAPESENSE_PLANT_STATE"));
  EXPECT_THROW(driver_.CommandTargets(std::vector<double>(4, 1.0)), ActuatorError);
  EXPECT_THROW(driver_.ReadPositions(), ActuatorError);
  // Answers again: nothing moves until Connect().
  plant_.set_answering(true);
  Run(0.05);
  EXPECT_EQ(driver_.Status().state, ActuatorState::kDisconnected);
  plant_.Tick();  // a state from now on
  driver_.Connect();
  EXPECT_TRUE(driver_.Status().ok());
}

TEST_F(RigPlantDriverTest, ThePlantsFaultsAndAWrongSizeAreFaults) {
  plant_.Tick();
  driver_.Connect();
  tendon_state_t state{};
  state.num_tendons = 4;
  state.displacement_mm = {0, 0, 0, 0};
  state.tension_n = {1, 1, 1, 1};
  state.fault = {0, 0, tendon_state_t::FAULT_DRIVE, 0};
  bus_.Publish(channels::kPlantState, state);
  while (bus_.Handle(0) > 0) {
  }
  ActuatorStatus status = driver_.Status();
  EXPECT_EQ(status.state, ActuatorState::kFault);
  EXPECT_THAT(status.reason, HasSubstr("fault on tendon 2"));
  EXPECT_THROW(driver_.CommandTargets(std::vector<double>(4, 1.0)), ActuatorError);
  EXPECT_NO_THROW(driver_.ReadPositions()) << "positions stay readable in a fault";

  plant_.Tick();  // healthy again; Connect() resets
  driver_.Connect();
  EXPECT_TRUE(driver_.Status().ok());
  state.num_tendons = 3;
  state.displacement_mm = {0, 0, 0};
  state.tension_n = {1, 1, 1};
  state.fault = {0, 0, 0};
  bus_.Publish(channels::kPlantState, state);
  while (bus_.Handle(0) > 0) {
  }
  status = driver_.Status();
  EXPECT_EQ(status.state, ActuatorState::kFault);
  EXPECT_THAT(status.reason, HasSubstr("the plant reports 3 tendons, the driver has 4"));
}

TEST(RigPlantDriverFactoryTest, MakesTheRigDriverAndLeavesTheRestToTheActuatorsFactory) {
  LcmBus bus("memq://");
  ActuatorOptions options;
  options.driver = "rig";
  std::unique_ptr<ActuatorDriver> rig = MakeControllerDriver(options, bus);
  EXPECT_NE(dynamic_cast<RigPlantDriver*>(rig.get()), nullptr);
  EXPECT_EQ(rig->description(), "rig plant over LCM");
  options.driver = "simulated";
  EXPECT_EQ(MakeControllerDriver(options, bus)->description(), "simulated tendons");
  options.driver = "ethercat";
  EXPECT_THROW(MakeControllerDriver(options, bus), std::invalid_argument);
}

template <class Message>
std::vector<uint8_t> Encode(const Message& message) {
  std::vector<uint8_t> bytes(static_cast<size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

// Every honest encoding passes; a cut or lengthened one does not; random
// corruption never makes a decode throw or allocate past the buffer.
template <class Message, class Make>
void CheckWire(Make make) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 30; ++trial) {
    std::vector<uint8_t> bytes = Encode(make(rng));
    Message decoded;
    EXPECT_EQ(DecodeMessage(bytes.data(), bytes.size(), &decoded), "");
    for (size_t cut : {size_t{1}, size_t{9}}) {
      if (cut < bytes.size()) {
        EXPECT_FALSE(WireCheck<Message>::Plausible(bytes.data(), bytes.size() - cut));
      }
    }
    bytes.push_back(0);
    EXPECT_FALSE(WireCheck<Message>::Plausible(bytes.data(), bytes.size()));
    bytes.pop_back();
    for (int corruption = 0; corruption < 40; ++corruption) {
      std::vector<uint8_t> broken = bytes;
      broken[rng() % broken.size()] ^= static_cast<uint8_t>(1u << (rng() % 8));
      if (DecodeMessage(broken.data(), broken.size(), &decoded).empty()) {
        EXPECT_LE(decoded.displacement_mm.size() * sizeof(double), broken.size());
      }
    }
  }
}

TEST(TendonWireCheckTest, CountsThatDoNotFitTheBufferAreRefused) {
  CheckWire<tendon_command_t>([](std::mt19937& rng) {
    tendon_command_t command{};
    command.num_tendons = static_cast<int32_t>(rng() % 9);
    command.displacement_mm.assign(static_cast<size_t>(command.num_tendons), 1.5);
    command.mode = tendon_command_t::MODE_CLOSED_LOOP;
    return command;
  });
  CheckWire<tendon_state_t>([](std::mt19937& rng) {
    tendon_state_t state{};
    state.num_tendons = static_cast<int32_t>(rng() % 9);
    state.displacement_mm.assign(static_cast<size_t>(state.num_tendons), 1.5);
    state.tension_n.assign(static_cast<size_t>(state.num_tendons), 0.5);
    state.fault.assign(static_cast<size_t>(state.num_tendons), 0);
    return state;
  });
  // A count of two billion tendons in a 40-byte buffer: refused before any allocation.
  tendon_state_t state{};
  std::vector<uint8_t> bytes = Encode(state);
  // Past the hash and the header.
  bytes[8 + static_cast<size_t>(state.header._getEncodedSizeNoHash())] = 0x7f;
  tendon_state_t decoded;
  EXPECT_THAT(DecodeMessage(bytes.data(), bytes.size(), &decoded), HasSubstr("lengths do not fit"));
}

}  // namespace
}  // namespace shapesense
