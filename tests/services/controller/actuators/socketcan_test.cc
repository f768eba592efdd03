// SocketCAN for real: the error where the kernel has no CAN (as on the build
// machine) or lacks the interface is clear, and on vcan0, where a kernel has
// it, the CANopen master brings up simulated CiA 402 drives and moves them.
// That last test skips, saying why, where vcan0 is missing.
#include "runtime/devices/socketcan_bus.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <thread>

#include "services/controller/actuators/canopen_driver.h"
#include "services/rig_sim/actuators/simulated_cia402_drive.h"

namespace shapesense {
namespace {

using ::testing::AnyOf;
using ::testing::HasSubstr;

TEST(SocketCanTest, AMissingInterfaceOrKernelSupportIsAClearError) {
  try {
    OpenSocketCanBus("shapesense9");
    FAIL() << "expected CanBusError";
  } catch (const CanBusError& e) {
    EXPECT_THAT(e.what(), AnyOf(HasSubstr("SocketCAN unavailable: this kernel has no CAN support"),
                                HasSubstr("no CAN interface named 'shapesense9'")));
  }
}

TEST(SocketCanTest, TheDriverReportsItAtConnect) {
  CanOpenOptions options;
  options.interface = "shapesense9";
  options.node_ids = {1};
  CanOpenActuatorDriver driver(
      options, [] { return OpenSocketCanBus("shapesense9"); }, "socketcan shapesense9");
  try {
    driver.Connect();
    FAIL() << "expected ActuatorError";
  } catch (const ActuatorError& e) {
    EXPECT_THAT(e.what(), HasSubstr("socketcan shapesense9: "));
  }
  EXPECT_EQ(driver.Status().state, ActuatorState::kDisconnected);
}

TEST(SocketCanTest, DrivesOnVcan0) {
  std::unique_ptr<CanBus> probe;
  try {
    probe = OpenSocketCanBus("vcan0");
  } catch (const CanBusError& e) {
    GTEST_SKIP() << "SKIPPED: the SocketCAN test needs vcan0 and this machine has none: "
                 << e.what()
                 << ". To run it: modprobe vcan && ip link add dev vcan0 type vcan && ip link "
                    "set up vcan0. The same master and drives run on the in-memory bus in "
                    "canopen_driver_test.";
  }
  std::vector<std::unique_ptr<SimulatedCia402Drive>> drives;
  for (const int id : {1, 2}) {
    SimulatedDriveOptions drive;
    drive.node_id = id;
    drives.push_back(std::make_unique<SimulatedCia402Drive>(OpenSocketCanBus("vcan0"), drive));
    drives.back()->PowerOn();
  }
  CanOpenOptions options;
  options.interface = "vcan0";
  options.node_ids = {1, 2};
  options.profile_velocity_mm_s = 100.0;
  options.heartbeat_timeout_s = 1.0;
  options.sdo_timeout_s = options.pdo_timeout_s = 0.5;
  CanOpenActuatorDriver driver(
      options, [] { return OpenSocketCanBus("vcan0"); }, "socketcan vcan0");
  driver.Connect();
  const std::vector<double> targets = {0.5, -0.5};
  driver.CommandTargets(targets);
  std::vector<double> mm;
  for (int i = 0; i < 300 && mm != targets; ++i) {
    mm = driver.ReadPositions().mm;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(mm, targets);
  drives[1]->InjectFault(0x3210);
  ActuatorStatus status = driver.Status();
  for (int i = 0; i < 500 && status.ok(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    status = driver.Status();
  }
  EXPECT_EQ(status.state, ActuatorState::kFault);
  EXPECT_EQ(status.code, 0x3210u);
}

}  // namespace
}  // namespace shapesense
