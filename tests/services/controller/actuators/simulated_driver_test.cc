// The simulated driver: the first-order lag is exact whatever the sampling,
// the plant sees what the driver reports, and faults and a cut link refuse
// targets until Connect().
#include "services/controller/actuators/simulated_driver.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace shapesense {
namespace {

using ::testing::HasSubstr;

class SimulatedDriverTest : public ::testing::Test {
 protected:
  SimulatedDriverTest()
      : driver_(
            3, Options(),
            [this](std::span<const double> mm, int64_t utime) {
              plant_mm_.assign(mm.begin(), mm.end());
              plant_utime_ = utime;
            },
            [this] { return now_; }) {}

  static SimulatedActuatorOptions Options() {
    SimulatedActuatorOptions options;
    options.time_constant_s = 0.2;
    return options;
  }

  int64_t now_ = 1'700'000'000'000'000;
  std::vector<double> plant_mm_;
  int64_t plant_utime_ = 0;
  SimulatedActuatorDriver driver_;
};

TEST_F(SimulatedDriverTest, TheLagIsExactForAnySampling) {
  std::mt19937 rng(31);
  driver_.Connect();
  const std::vector<double> step = {10.0, -4.0, 0.5};
  const int64_t start = now_;
  driver_.CommandTargets(step);
  for (int sample = 0; sample < 40; ++sample) {
    now_ += std::uniform_int_distribution<int64_t>(1, 60'000)(rng);
    const ActuatorPositions positions = driver_.ReadPositions();
    const double t = static_cast<double>(now_ - start) * 1e-6;
    for (size_t i = 0; i < step.size(); ++i) {
      EXPECT_NEAR(positions.mm[i], step[i] * (1.0 - std::exp(-t / 0.2)), 1e-9);
    }
    EXPECT_EQ(positions.utime, now_);
    EXPECT_EQ(plant_mm_, positions.mm) << "the plant sees what the driver reports";
    EXPECT_EQ(plant_utime_, now_);
  }
}

TEST_F(SimulatedDriverTest, ANewCommandStartsFromWhereTheTendonIs) {
  driver_.Connect();
  driver_.CommandTargets(std::vector<double>{10.0, 10.0, 10.0});
  now_ += 200'000;  // one time constant
  driver_.CommandTargets(std::vector<double>{0.0, 0.0, 0.0});
  const double at_switch = 10.0 * (1.0 - std::exp(-1.0));
  now_ += 200'000;
  EXPECT_NEAR(driver_.ReadPositions().mm[0], at_switch * std::exp(-1.0), 1e-9);
}

TEST_F(SimulatedDriverTest, WithoutLagATendonIsWhereItIsCommanded) {
  SimulatedActuatorDriver immediate(2, SimulatedActuatorOptions{0.0}, {}, [this] { return now_; });
  immediate.Connect();
  immediate.CommandTargets(std::vector<double>{1.5, -2.5});
  EXPECT_EQ(immediate.ReadPositions().mm, (std::vector<double>{1.5, -2.5}));
}

TEST_F(SimulatedDriverTest, StopHolds) {
  driver_.Connect();
  driver_.CommandTargets(std::vector<double>{5.0, 5.0, 5.0});
  now_ += 100'000;
  driver_.Stop();
  const std::vector<double> held = driver_.ReadPositions().mm;
  now_ += 1'000'000;
  EXPECT_EQ(driver_.ReadPositions().mm, held);
  EXPECT_TRUE(driver_.Status().ok()) << "a stop is no fault";
  driver_.CommandTargets(std::vector<double>{5.0, 5.0, 5.0});
}

TEST_F(SimulatedDriverTest, FaultsAndACutLinkRefuseTargetsUntilConnect) {
  EXPECT_THROW(driver_.CommandTargets(std::vector<double>(3, 0.0)), ActuatorError)
      << "not connected yet";
  driver_.Connect();
  driver_.InjectFault(42, "tendon 2 snapped");
  EXPECT_EQ(driver_.Status().state, ActuatorState::kFault);
  EXPECT_EQ(driver_.Status().code, 42u);
  try {
    driver_.CommandTargets(std::vector<double>(3, 1.0));
    FAIL() << "expected ActuatorError";
  } catch (const ActuatorError& e) {
    EXPECT_THAT(e.what(),
                HasSubstr("target refused while fault (simulated tendons: tendon 2 snapped)"));
  }
  EXPECT_EQ(driver_.targets(), (std::vector<double>{0.0, 0.0, 0.0}));
  EXPECT_NO_THROW(driver_.ReadPositions()) << "positions stay readable in a fault";
  driver_.Connect();
  driver_.CommandTargets(std::vector<double>(3, 1.0));
  driver_.CutLink("cable pulled");
  EXPECT_EQ(driver_.Status().state, ActuatorState::kDisconnected);
  EXPECT_FALSE(driver_.Health().link_alive);
  EXPECT_THROW(driver_.ReadPositions(), ActuatorError);
  driver_.Connect();
  EXPECT_TRUE(driver_.Status().ok());
  EXPECT_EQ(driver_.Health().connects, 3);
}

TEST_F(SimulatedDriverTest, BadTargetsAreRefusedWithoutEffect) {
  driver_.Connect();
  EXPECT_THROW(driver_.CommandTargets(std::vector<double>{1.0, 2.0}), ActuatorError);
  EXPECT_THROW(driver_.CommandTargets(std::vector<double>{1.0, NAN, 2.0}), ActuatorError);
  EXPECT_EQ(driver_.targets(), (std::vector<double>{0.0, 0.0, 0.0}));
  EXPECT_TRUE(driver_.Status().ok());
}

}  // namespace
}  // namespace shapesense
