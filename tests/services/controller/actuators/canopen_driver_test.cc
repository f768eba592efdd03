// The CANopen master against simulated CiA 402 drives on the in-memory bus:
// bring-up through NMT and the state machine, targets that reach their
// positions through the set-point handshake, halt, and the faults: an EMCY,
// a lost heartbeat, a restarted drive, a cut cable, a missing drive, SDO
// aborts at configuration; each a clear error after which every drive is
// stopped and no target goes out until Connect().
#include "services/controller/actuators/canopen_driver.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <random>
#include <thread>

#include "services/rig_sim/actuators/in_memory_can_bus.h"
#include "services/rig_sim/actuators/simulated_cia402_drive.h"

namespace shapesense {
namespace {

using cia402::State;
using ::testing::HasSubstr;

constexpr double kCountsPerMm = 1000.0;

// Margins for sanitizer builds on a shared, busy machine; nothing here
// depends on them being tight.
CanOpenOptions TestOptions(const std::vector<int>& ids) {
  CanOpenOptions options;
  options.interface = "memory";
  options.node_ids = ids;
  options.counts_per_mm = kCountsPerMm;
  options.profile_velocity_mm_s = 100.0;
  options.heartbeat_period_s = 0.05;
  options.heartbeat_timeout_s = 1.0;
  options.sdo_timeout_s = 0.5;
  options.pdo_timeout_s = 0.5;
  options.boot_timeout_s = 2.0;
  options.state_timeout_s = 2.0;
  return options;
}

// Drives on one in-memory bus and a master for them.
class CanRig {
 public:
  explicit CanRig(const std::vector<int>& ids, CanOpenOptions options = {},
                  SimulatedDriveOptions drive = {}, bool power_on = true) {
    if (options.interface != "memory") options = TestOptions(ids);
    std::mt19937 rng(ids.size());
    for (const int id : ids) {
      drive.node_id = id;
      drive.initial_position = std::uniform_int_distribution<int32_t>(-5000, 5000)(rng);
      drives_.push_back(std::make_unique<SimulatedCia402Drive>(
          network_.Attach("node " + std::to_string(id)), drive));
      if (power_on) drives_.back()->PowerOn();
    }
    driver_ = std::make_unique<CanOpenActuatorDriver>(
        options, [this] { return network_.Attach("master"); }, "memory bus");
  }

  CanOpenActuatorDriver& driver() { return *driver_; }
  SimulatedCia402Drive& drive(size_t i) { return *drives_.at(i); }
  size_t size() const { return drives_.size(); }
  InMemoryCanNetwork& network() { return network_; }

  // Status() until it is not ok, bounded.
  ActuatorStatus AwaitTrouble() {
    for (int i = 0; i < 1000; ++i) {
      ActuatorStatus status = driver_->Status();
      if (!status.ok()) return status;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return driver_->Status();
  }

  // Until drive `i` is in `state`, bounded; its state then.
  State AwaitDriveState(size_t i, State state) {
    for (int n = 0; n < 1000 && drives_[i]->state() != state; ++n) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return drives_[i]->state();
  }

  std::vector<int64_t> Setpoints() const {
    std::vector<int64_t> counts;
    for (const auto& drive : drives_) counts.push_back(drive->counters().setpoints);
    return counts;
  }

 private:
  InMemoryCanNetwork network_;  // outlives the drives and the master
  std::vector<std::unique_ptr<SimulatedCia402Drive>> drives_;
  std::unique_ptr<CanOpenActuatorDriver> driver_;
};

std::vector<double> AwaitPositions(ActuatorDriver& driver, const std::vector<double>& target) {
  std::vector<double> mm;
  for (int i = 0; i < 500; ++i) {
    mm = driver.ReadPositions().mm;
    if (mm == target) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return mm;
}

TEST(CanOpenDriverTest, BringsEveryDriveUpThroughNmtAndTheStateMachine) {
  CanRig rig({1, 2, 3, 4});
  rig.driver().Connect();
  EXPECT_TRUE(rig.driver().Status().ok());
  const ActuatorPositions positions = rig.driver().ReadPositions();
  for (size_t i = 0; i < rig.size(); ++i) {
    SimulatedCia402Drive& drive = rig.drive(i);
    EXPECT_EQ(drive.nmt_state(), static_cast<uint8_t>(canopen::NmtState::kOperational));
    EXPECT_EQ(drive.state(), State::kOperationEnabled);
    EXPECT_EQ(drive.Object(cia402::kModesOfOperationDisplay, 0), 1u);
    EXPECT_EQ(drive.Object(0x1017, 0), 50u) << "heartbeat producer time, ms";
    EXPECT_EQ(drive.Object(cia402::kProfileVelocity, 0), 100000u) << "100 mm/s in counts/s";
    EXPECT_EQ(drive.Object(0x1400, 2), 1u) << "RPDO1 made synchronous";
    EXPECT_EQ(drive.Object(0x1600, 1), 0x60400010u);
    EXPECT_EQ(drive.Object(0x1A00, 2), 0x60640020u);
    EXPECT_EQ(drive.setpoint(), drive.position()) << "enabled holding where it stood";
    EXPECT_DOUBLE_EQ(positions.mm[i], drive.position() / kCountsPerMm);
  }
  EXPECT_GT(positions.utime, 0);
  const ActuatorHealth health = rig.driver().Health();
  EXPECT_TRUE(health.link_alive);
  EXPECT_EQ(health.connects, 1);
  EXPECT_EQ(health.timeouts, 0);
}

TEST(CanOpenDriverTest, TargetsReachTheirPositionsThroughTheHandshake) {
  CanRig rig({1, 2, 3});
  rig.driver().Connect();
  std::mt19937 rng(71);
  std::uniform_int_distribution<int> counts(-8000, 8000);
  for (int round = 1; round <= 4; ++round) {
    std::vector<double> targets;
    for (size_t i = 0; i < rig.size(); ++i) targets.push_back(counts(rng) / kCountsPerMm);
    rig.driver().CommandTargets(targets);
    for (size_t i = 0; i < rig.size(); ++i) {
      EXPECT_EQ(rig.drive(i).setpoint(), std::lround(targets[i] * kCountsPerMm))
          << "taken when the call returns";
      EXPECT_EQ(rig.drive(i).counters().setpoints, round) << "one set-point per command";
    }
    EXPECT_EQ(AwaitPositions(rig.driver(), targets), targets);
  }
  EXPECT_TRUE(rig.driver().Status().ok());
  EXPECT_GT(rig.driver().Health().round_trip_us, 0);
}

TEST(CanOpenDriverTest, StopHaltsEveryDriveAndTheNextTargetMovesAgain) {
  CanRig rig({1, 2});
  rig.driver().Connect();
  rig.driver().CommandTargets(std::vector<double>{1000.0, -1000.0});  // 10 s away at 100 mm/s
  rig.driver().Stop();
  const std::vector<double> held = rig.driver().ReadPositions().mm;
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(rig.driver().ReadPositions().mm, held) << "halted drives do not move";
  EXPECT_TRUE(rig.driver().Status().ok()) << "a stop is no fault";
  EXPECT_EQ(rig.drive(0).state(), State::kOperationEnabled);
  const std::vector<double> targets = {0.5, -0.5};
  rig.driver().CommandTargets(targets);
  EXPECT_EQ(AwaitPositions(rig.driver(), targets), targets);
}

TEST(CanOpenDriverTest, AnEmcyIsAFaultThatQuickStopsEveryDriveUntilConnect) {
  CanRig rig({1, 2, 3});
  rig.driver().Connect();
  rig.driver().CommandTargets(std::vector<double>{1.0, 1.0, 1.0});
  rig.drive(1).InjectFault(0x2310);
  const ActuatorStatus status = rig.AwaitTrouble();
  EXPECT_EQ(status.state, ActuatorState::kFault);
  EXPECT_EQ(status.code, 0x2310u);
  EXPECT_THAT(status.reason,
              HasSubstr("node 2: EMCY 0x2310 (current, device output side), error register 0x03"));
  EXPECT_EQ(rig.AwaitDriveState(0, State::kQuickStopActive), State::kQuickStopActive);
  EXPECT_EQ(rig.AwaitDriveState(2, State::kQuickStopActive), State::kQuickStopActive);
  EXPECT_EQ(rig.drive(1).state(), State::kFault);
  const std::vector<int64_t> setpoints = rig.Setpoints();
  try {
    rig.driver().CommandTargets(std::vector<double>{2.0, 2.0, 2.0});
    FAIL() << "expected ActuatorError";
  } catch (const ActuatorError& e) {
    EXPECT_THAT(e.what(), HasSubstr("target refused while fault (memory bus: node 2: EMCY 0x2310"));
  }
  EXPECT_EQ(rig.Setpoints(), setpoints) << "no set-point after the fault";
  EXPECT_EQ(rig.driver().ReadPositions().mm.size(), 3u) << "positions stay readable in a fault";

  rig.driver().Connect();  // the explicit reset: NMT, fault reset, enable
  EXPECT_TRUE(rig.driver().Status().ok());
  for (size_t i = 0; i < rig.size(); ++i) EXPECT_EQ(rig.drive(i).state(), State::kOperationEnabled);
  const std::vector<double> targets = {-0.25, 0.25, 0.0};
  rig.driver().CommandTargets(targets);
  EXPECT_EQ(AwaitPositions(rig.driver(), targets), targets);
}

TEST(CanOpenDriverTest, ALostHeartbeatIsAFaultNamingTheDrive) {
  CanRig rig({1, 2, 3});
  rig.driver().Connect();
  rig.drive(2).PowerOff();
  const ActuatorStatus status = rig.AwaitTrouble();
  EXPECT_EQ(status.state, ActuatorState::kFault);
  EXPECT_THAT(status.reason, HasSubstr("node 3: heartbeat lost (none for "));
  EXPECT_THAT(status.reason, HasSubstr("timeout 1.00 s)"));
  EXPECT_EQ(rig.AwaitDriveState(0, State::kQuickStopActive), State::kQuickStopActive);
  EXPECT_THROW(rig.driver().CommandTargets(std::vector<double>(3, 0.0)), ActuatorError);
  rig.drive(2).PowerOn();
  rig.driver().Connect();
  EXPECT_TRUE(rig.driver().Status().ok());
}

TEST(CanOpenDriverTest, ADriveThatRestartsIsAFault) {
  CanRig rig({1, 2});
  rig.driver().Connect();
  rig.drive(0).PowerOff();
  rig.drive(0).PowerOn();  // boot-up message: its configuration is gone
  const ActuatorStatus status = rig.AwaitTrouble();
  EXPECT_EQ(status.state, ActuatorState::kFault);
  EXPECT_THAT(status.reason, HasSubstr("node 1 restarted (boot-up message)"));
}

TEST(CanOpenDriverTest, ACutCableIsADisconnectAndConnectRecovers) {
  CanRig rig({1, 2});
  rig.driver().Connect();
  rig.network().SetLinkUp("master", false);
  try {
    rig.driver().CommandTargets(std::vector<double>{1.0, 1.0});
    FAIL() << "expected ActuatorError";
  } catch (const ActuatorError& e) {
    EXPECT_THAT(e.what(), HasSubstr("memory bus: memory:master: link down"));
  }
  EXPECT_EQ(rig.driver().Status().state, ActuatorState::kDisconnected);
  EXPECT_FALSE(rig.driver().Health().link_alive);
  EXPECT_THROW(rig.driver().ReadPositions(), ActuatorError);
  rig.network().SetLinkUp("master", true);
  rig.driver().Connect();
  const std::vector<double> targets = {0.125, -0.125};
  rig.driver().CommandTargets(targets);
  EXPECT_EQ(AwaitPositions(rig.driver(), targets), targets);
}

TEST(CanOpenDriverTest, AMissingDriveIsNamedAtConnect) {
  CanRig rig({1, 2}, {}, {}, /*power_on=*/false);
  rig.drive(0).PowerOn();
  CanOpenOptions options = TestOptions({1, 2});
  options.boot_timeout_s = 0.2;
  CanOpenActuatorDriver driver(
      options, [&] { return rig.network().Attach("master"); }, "bus");
  try {
    driver.Connect();
    FAIL() << "expected ActuatorError";
  } catch (const ActuatorError& e) {
    EXPECT_THAT(e.what(),
                HasSubstr("bus: node 2: no boot-up message within 0.20 s of the NMT reset"));
  }
  EXPECT_EQ(driver.Status().state, ActuatorState::kDisconnected);
}

TEST(CanOpenDriverTest, AnSdoAbortAtConfigurationIsReportedWithItsCode) {
  SimulatedDriveOptions slow;
  slow.max_velocity_counts_s = 50000;  // the config asks for 100 mm/s = 100000 counts/s
  CanRig rig({1, 2}, {}, slow);
  try {
    rig.driver().Connect();
    FAIL() << "expected ActuatorError";
  } catch (const ActuatorError& e) {
    EXPECT_THAT(e.what(), HasSubstr("node 1: SDO write 6081:00 = 100000 aborted: 0x06090031 "
                                    "(value of parameter written too high)"));
  }
  EXPECT_EQ(rig.driver().Status().state, ActuatorState::kFault);
  EXPECT_EQ(rig.driver().Status().code, 0x06090031u);
}

TEST(CanOpenDriverTest, ANodeThatIsNoCia402DriveIsRefused) {
  SimulatedDriveOptions io_module;
  io_module.device_type = 0x000F0191;  // CiA 401
  CanRig rig({5}, {}, io_module);
  try {
    rig.driver().Connect();
    FAIL() << "expected ActuatorError";
  } catch (const ActuatorError& e) {
    EXPECT_THAT(e.what(), HasSubstr("node 5: not a CiA 402 drive (device type 0x000F0191)"));
  }
}

TEST(CanOpenDriverTest, WithoutPdoConfigurationTheDrivesDefaultsAreChecked) {
  CanOpenOptions options = TestOptions({1, 2});
  options.configure_pdos = false;
  CanRig rig({1, 2}, options);
  rig.driver().Connect();
  EXPECT_EQ(rig.drive(0).Object(0x1400, 2), 0xFFu) << "left as the drive has it";
  const std::vector<double> targets = {0.75, -0.75};
  rig.driver().CommandTargets(targets);
  EXPECT_EQ(AwaitPositions(rig.driver(), targets), targets);
}

TEST(CanOpenDriverTest, BadTargetsAreRefusedWithoutSendingAnything) {
  CanRig rig({1, 2});
  rig.driver().Connect();
  const std::vector<int64_t> setpoints = rig.Setpoints();
  EXPECT_THROW(rig.driver().CommandTargets(std::vector<double>{1.0}), ActuatorError);
  EXPECT_THROW(rig.driver().CommandTargets(std::vector<double>{1.0, 1e12}), ActuatorError);
  EXPECT_EQ(rig.Setpoints(), setpoints);
  EXPECT_TRUE(rig.driver().Status().ok());
}

TEST(CanOpenDriverTest, CycleTimesOnTheInMemoryBus) {
  CanRig rig({1, 2, 3, 4});
  rig.driver().Connect();
  std::vector<int64_t> sync_us, command_us;
  for (int i = 0; i < 200; ++i) {
    rig.driver().ReadPositions();
    sync_us.push_back(rig.driver().Health().round_trip_us);
    const auto start = std::chrono::steady_clock::now();
    rig.driver().CommandTargets(std::vector<double>(4, 0.001 * (i % 10)));
    command_us.push_back(std::chrono::duration_cast<std::chrono::microseconds>(
                             std::chrono::steady_clock::now() - start)
                             .count());
  }
  std::sort(sync_us.begin(), sync_us.end());
  std::sort(command_us.begin(), command_us.end());
  // Reported, not asserted: threads on a shared machine, not a 1 Mbit/s bus.
  std::cout << "in-memory bus, 4 drives: SYNC -> 4 TPDOs (us): median " << sync_us[100] << ", p99 "
            << sync_us[198] << "; CommandTargets (2 handshake SYNCs, us): median "
            << command_us[100] << ", p99 " << command_us[198] << std::endl;
  EXPECT_TRUE(rig.driver().Status().ok());
  for (size_t i = 0; i < rig.size(); ++i) EXPECT_EQ(rig.drive(i).counters().setpoints, 200);
}

}  // namespace
}  // namespace shapesense
