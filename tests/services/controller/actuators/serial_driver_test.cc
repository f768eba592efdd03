// The serial driver end to end over a real pseudo-terminal against the
// simulated actuator: targets reach the axes and positions read back,
// damaged lines in either direction are rejected, counted and retried, a
// device fault or a refusal stops commanding, a cut link (the pty's master
// closed) is a clear disconnect, and Connect() finds the actuator again when
// it comes back behind the same path. Also the shapesense-actuator-sim program.
#include "services/controller/actuators/serial_driver.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <random>
#include <thread>

#include "libs/actuation/line_protocol.h"
#include "runtime/devices/serial_port.h"
#include "runtime/process/child_process.h"
#include "services/rig_sim/actuators/simulated_serial_actuator.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// An actuator "plugged in" behind a stable path (a symlink to its pty, as
// udev's /dev/serial/by-id links are), which can be unplugged and plugged back.
class SerialRig {
 public:
  explicit SerialRig(int axes = 4) : axes_(axes) {
    dir_ = fs::temp_directory_path() /
           ("shapesense-serial-" + std::to_string(getpid()) + "-" + std::to_string(counter_++));
    fs::create_directories(dir_);
    PlugIn();
  }
  ~SerialRig() {
    Unplug();
    fs::remove_all(dir_);
  }

  void PlugIn() {
    pty_ = std::make_unique<PseudoTerminal>();
    SimulatedSerialActuatorOptions options;
    options.axes = axes_;
    options.max_speed_mm_s = 200.0;
    actuator_ = std::make_unique<SimulatedSerialActuator>(pty_->master_fd(), options);
    actuator_->Start();
    fs::remove(link());
    fs::create_symlink(pty_->slave_path(), link());
  }
  // The cable is cut: the actuator's end of the pty closes.
  void Unplug() {
    if (actuator_) actuator_->Stop();
    actuator_.reset();
    pty_.reset();
  }

  fs::path link() const { return dir_ / "actuator"; }
  SimulatedSerialActuator& actuator() { return *actuator_; }

  SerialActuatorOptions Options() const {
    SerialActuatorOptions options;
    options.device = link().string();
    options.reply_timeout_s = 0.5;  // generous: sanitizer builds on a busy machine
    options.retries = 2;
    options.connect_timeout_s = 1.0;
    options.device_watchdog_s = 5.0;
    return options;
  }

 private:
  static inline int counter_ = 0;
  int axes_;
  fs::path dir_;
  std::unique_ptr<PseudoTerminal> pty_;
  std::unique_ptr<SimulatedSerialActuator> actuator_;
};

// Reads positions until every axis is within `tolerance` of `target` (bounded).
std::vector<double> AwaitPositions(ActuatorDriver& driver, const std::vector<double>& target,
                                   double tolerance) {
  std::vector<double> mm;
  for (int i = 0; i < 500; ++i) {
    mm = driver.ReadPositions().mm;
    bool there = true;
    for (size_t axis = 0; axis < target.size(); ++axis) {
      there = there && std::abs(mm[axis] - target[axis]) <= tolerance;
    }
    if (there) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return mm;
}

std::vector<double> RandomTargets(std::mt19937& rng, int axes) {
  std::uniform_real_distribution<double> mm(-20.0, 20.0);
  std::vector<double> targets;
  targets.reserve(static_cast<size_t>(axes));
  for (int i = 0; i < axes; ++i) {
    targets.push_back(std::stod(serial_protocol::FormatMm(mm(rng))));  // what the line carries
  }
  return targets;
}

TEST(SerialDriverTest, TargetsReachTheAxesAndPositionsReadBack) {
  SerialRig rig;
  SerialActuatorDriver driver(rig.Options(), 4);
  driver.Connect();
  EXPECT_TRUE(driver.Status().ok());
  std::mt19937 rng(41);
  int64_t last_utime = 0;
  for (int round = 0; round < 3; ++round) {
    const std::vector<double> targets = RandomTargets(rng, 4);
    driver.CommandTargets(targets);
    EXPECT_EQ(rig.actuator().targets(), targets) << "every axis got its target";
    const std::vector<double> reached = AwaitPositions(driver, targets, 1e-9);
    EXPECT_EQ(reached, targets);
    const ActuatorPositions positions = driver.ReadPositions();
    EXPECT_GT(positions.utime, last_utime);
    last_utime = positions.utime;
  }
  const ActuatorHealth health = driver.Health();
  EXPECT_TRUE(health.link_alive);
  EXPECT_EQ(health.corrupt_replies, 0);
  EXPECT_EQ(health.timeouts, 0);
  EXPECT_GT(health.last_contact_utime, 0);
}

TEST(SerialDriverTest, RoundTripsOverThePty) {
  SerialRig rig;
  SerialActuatorDriver driver(rig.Options(), 4);
  driver.Connect();
  std::vector<int64_t> read_us, command_us;
  for (int i = 0; i < 300; ++i) {
    driver.ReadPositions();
    read_us.push_back(driver.Health().round_trip_us);
    const auto start = std::chrono::steady_clock::now();
    driver.CommandTargets(std::vector<double>(4, 0.01 * (i % 10)));
    command_us.push_back(std::chrono::duration_cast<std::chrono::microseconds>(
                             std::chrono::steady_clock::now() - start)
                             .count());
  }
  std::sort(read_us.begin(), read_us.end());
  std::sort(command_us.begin(), command_us.end());
  // Reported, not asserted (no timing assertions): the numbers of docs/actuators.md.
  std::cout << "pty round trip P? (us): median " << read_us[150] << ", p99 " << read_us[297]
            << "; 4-axis CommandTargets (us): median " << command_us[150] << ", p99 "
            << command_us[297] << std::endl;
  EXPECT_EQ(driver.Health().timeouts, 0);
}

TEST(SerialDriverTest, DamagedRepliesAreRejectedCountedAndRetried) {
  SerialRig rig;
  SerialActuatorDriver driver(rig.Options(), 4);
  driver.Connect();
  rig.actuator().CorruptReplies(2);
  const ActuatorPositions positions = driver.ReadPositions();  // the third try gets through
  EXPECT_EQ(positions.mm.size(), 4u);
  EXPECT_EQ(driver.Health().corrupt_replies, 2);
  EXPECT_EQ(driver.Health().retries, 2);
  EXPECT_TRUE(driver.Status().ok());
}

TEST(SerialDriverTest, DamagedRequestsAreRefusedByTheActuatorAndSentAgain) {
  SerialRig rig;
  SerialActuatorDriver driver(rig.Options(), 4);
  driver.Connect();
  rig.actuator().CorruptRequests(1);
  driver.CommandTargets(std::vector<double>{1.0, 2.0, 3.0, 4.0});
  EXPECT_EQ(rig.actuator().targets(), (std::vector<double>{1.0, 2.0, 3.0, 4.0}));
  EXPECT_EQ(rig.actuator().counters().checksum_errors, 1);
  EXPECT_EQ(driver.Health().rejected_requests, 1);
  EXPECT_EQ(driver.Health().retries, 1);
}

TEST(SerialDriverTest, RepliesDamagedBeyondTheRetriesAreALostLink) {
  SerialRig rig;
  SerialActuatorDriver driver(rig.Options(), 4);
  driver.Connect();
  rig.actuator().CorruptReplies(3);
  try {
    driver.ReadPositions();
    FAIL() << "expected ActuatorError";
  } catch (const ActuatorError& e) {
    EXPECT_THAT(e.what(), HasSubstr("no valid reply to 'P?' in 3 tries of 500 ms (link lost?)"));
  }
  EXPECT_EQ(driver.Status().state, ActuatorState::kDisconnected);
  EXPECT_EQ(driver.Health().corrupt_replies, 3);
}

TEST(SerialDriverTest, ASilentActuatorTimesOutAndIsDisconnected) {
  SerialRig rig;
  SerialActuatorOptions options = rig.Options();
  options.reply_timeout_s = 0.05;
  SerialActuatorDriver driver(options, 4);
  driver.Connect();
  rig.actuator().SetMuted(true);
  EXPECT_THROW(driver.ReadPositions(), ActuatorError);
  EXPECT_EQ(driver.Health().timeouts, 3);
  EXPECT_EQ(driver.Status().state, ActuatorState::kDisconnected);
  EXPECT_THAT(driver.Status().reason, HasSubstr("no valid reply to 'P?' in 3 tries of 50 ms"));
}

TEST(SerialDriverTest, ADeviceFaultStopsCommandingUntilConnect) {
  SerialRig rig;
  SerialActuatorDriver driver(rig.Options(), 4);
  driver.Connect();
  driver.CommandTargets(std::vector<double>{5.0, 5.0, 5.0, 5.0});
  rig.actuator().InjectFault(7, "motor 2 over temperature");
  const ActuatorStatus status = driver.Status();
  EXPECT_EQ(status.state, ActuatorState::kFault);
  EXPECT_EQ(status.code, 7u);
  EXPECT_THAT(status.reason, HasSubstr("actuator fault 7: motor 2 over temperature"));
  const int64_t targets_before = rig.actuator().counters().targets;
  const int64_t refused_before = rig.actuator().counters().refused_targets;
  try {
    driver.CommandTargets(std::vector<double>{9.0, 9.0, 9.0, 9.0});
    FAIL() << "expected ActuatorError";
  } catch (const ActuatorError& e) {
    EXPECT_THAT(e.what(), HasSubstr("target refused while fault"));
  }
  EXPECT_EQ(rig.actuator().counters().targets, targets_before) << "nothing was sent";
  EXPECT_EQ(rig.actuator().counters().refused_targets, refused_before);
  EXPECT_EQ(driver.ReadPositions().mm.size(), 4u) << "positions stay readable in a fault";
  driver.Connect();  // the explicit reset: R clears the actuator's fault
  EXPECT_TRUE(driver.Status().ok());
  driver.CommandTargets(std::vector<double>{1.0, 1.0, 1.0, 1.0});
  EXPECT_EQ(rig.actuator().targets(), (std::vector<double>{1.0, 1.0, 1.0, 1.0}));
}

TEST(SerialDriverTest, ARefusedTargetIsAFaultAndStops) {
  SerialRig rig;
  SerialActuatorDriver driver(rig.Options(), 4);
  driver.Connect();
  const int64_t stops_before = rig.actuator().counters().stops;
  try {
    driver.CommandTargets(std::vector<double>{1.0, 80.0, 1.0, 1.0});  // beyond ±50 mm of travel
    FAIL() << "expected ActuatorError";
  } catch (const ActuatorError& e) {
    EXPECT_THAT(e.what(), HasSubstr("the actuator refused 'T 1 80.0000': E 4 target"));
  }
  EXPECT_EQ(driver.Status().state, ActuatorState::kFault);
  EXPECT_EQ(driver.Status().code, 4u);
  EXPECT_EQ(rig.actuator().counters().stops, stops_before + 1) << "the driver sent X";
  EXPECT_EQ(rig.actuator().targets()[0], rig.actuator().positions()[0])
      << "axis 0, already on its way, holds";
}

TEST(SerialDriverTest, ACutLinkIsAClearDisconnectAndConnectFindsTheActuatorAgain) {
  SerialRig rig;
  SerialActuatorDriver driver(rig.Options(), 4);
  driver.Connect();
  driver.CommandTargets(std::vector<double>{2.0, 2.0, 2.0, 2.0});
  rig.Unplug();
  try {
    driver.CommandTargets(std::vector<double>{3.0, 3.0, 3.0, 3.0});
    FAIL() << "expected ActuatorError";
  } catch (const ActuatorError& e) {
    EXPECT_THAT(e.what(), HasSubstr("serial " + rig.link().string() + ": link cut"));
  }
  EXPECT_EQ(driver.Status().state, ActuatorState::kDisconnected);
  EXPECT_FALSE(driver.Health().link_alive);
  try {
    driver.CommandTargets(std::vector<double>{3.0, 3.0, 3.0, 3.0});
    FAIL() << "expected ActuatorError";
  } catch (const ActuatorError& e) {
    EXPECT_THAT(e.what(), HasSubstr("target refused while disconnected"));
    EXPECT_THAT(e.what(), HasSubstr("Connect() first"));
  }
  EXPECT_THROW(driver.Connect(), ActuatorError) << "the actuator is still away";
  rig.PlugIn();
  driver.Connect();
  EXPECT_TRUE(driver.Status().ok());
  const std::vector<double> targets = {4.0, -4.0, 4.0, -4.0};
  driver.CommandTargets(targets);
  EXPECT_EQ(AwaitPositions(driver, targets, 1e-9), targets);
  EXPECT_EQ(driver.Health().connects, 2);
}

TEST(SerialDriverTest, AnActuatorWithTooFewAxesIsRefusedAtConnect) {
  SerialRig rig(2);
  SerialActuatorDriver driver(rig.Options(), 4);
  try {
    driver.Connect();
    FAIL() << "expected ActuatorError";
  } catch (const ActuatorError& e) {
    EXPECT_THAT(e.what(), HasSubstr("the actuator has 2 axes, the configuration needs 4"));
  }
  EXPECT_EQ(driver.Status().state, ActuatorState::kDisconnected);
}

TEST(ActuatorSimProgramTest, ServesTheProtocolOnAPtyUntilStopped) {
  const fs::path link =
      fs::temp_directory_path() / ("shapesense-actuator-sim-" + std::to_string(getpid()));
  ChildProcess sim({ACTUATOR_SIM_BINARY, "--axes", "3", "--link", link.string()});
  ASSERT_TRUE(sim.WaitForLine("serial actuator on /dev/pts/", std::chrono::seconds(20)))
      << sim.output();
  EXPECT_THAT(sim.output(), HasSubstr("(3 axes), link " + link.string()));
  SerialActuatorOptions options;
  options.device = link.string();
  options.reply_timeout_s = 0.5;
  SerialActuatorDriver driver(options, 3);
  driver.Connect();
  const std::vector<double> targets = {1.0, -2.0, 3.0};
  driver.CommandTargets(targets);
  EXPECT_EQ(AwaitPositions(driver, targets, 1e-9), targets);
  EXPECT_EQ(sim.Stop(), 0);
  EXPECT_THROW(driver.ReadPositions(), ActuatorError);
  EXPECT_EQ(driver.Status().state, ActuatorState::kDisconnected);
  EXPECT_FALSE(fs::exists(fs::symlink_status(link))) << "the program removes its link";
}

}  // namespace
}  // namespace shapesense
