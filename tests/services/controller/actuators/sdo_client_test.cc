// The SDO client against the simulated drive's object dictionary: values
// round trip, and every refusal comes back as the CiA 301 abort code with its
// meaning, naming the node and the object; a silent node is a timeout.
#include "services/controller/actuators/sdo_client.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "libs/actuation/canopen.h"
#include "libs/actuation/cia402.h"
#include "services/rig_sim/actuators/in_memory_can_bus.h"
#include "services/rig_sim/actuators/simulated_cia402_drive.h"

namespace shapesense {
namespace {

using ::testing::HasSubstr;

class SdoClientTest : public ::testing::Test {
 protected:
  SdoClientTest()
      : master_(network_.Attach("master")),
        drive_(network_.Attach("drive 3"), DriveOptions()),
        sdo_(*master_, std::chrono::microseconds(500'000),
             [this](const CanFrame& frame) { other_frames_.push_back(frame); }) {
    drive_.PowerOn();
  }

  static SimulatedDriveOptions DriveOptions() {
    SimulatedDriveOptions options;
    options.node_id = 3;
    options.max_velocity_counts_s = 50000;
    return options;
  }

  // The abort code of a failing call, with its message checked.
  template <class Call>
  uint32_t AbortOf(Call&& call, const std::string& message) {
    try {
      call();
    } catch (const SdoError& e) {
      EXPECT_THAT(e.what(), HasSubstr(message));
      return e.abort_code();
    }
    ADD_FAILURE() << "expected SdoError: " << message;
    return 0;
  }

  InMemoryCanNetwork network_;
  std::unique_ptr<CanBus> master_;
  SimulatedCia402Drive drive_;
  std::vector<CanFrame> other_frames_;
  SdoClient sdo_;
};

TEST_F(SdoClientTest, ValuesRoundTripThroughTheDrive) {
  std::mt19937 rng(61);
  EXPECT_EQ(sdo_.Upload(3, 0x1000, 0), 0x00020192u);
  for (int trial = 0; trial < 20; ++trial) {
    const int32_t target = static_cast<int32_t>(rng());
    sdo_.Download(3, cia402::kTargetPosition, 0, static_cast<uint32_t>(target), 4);
    EXPECT_EQ(canopen::SignExtend(sdo_.Upload(3, cia402::kTargetPosition, 0), 4), target);
    const uint32_t period = rng() % 1000 + 1;
    sdo_.Download(3, 0x1017, 0, period, 2);
    EXPECT_EQ(drive_.Object(0x1017, 0), period);
  }
  EXPECT_FALSE(other_frames_.empty()) << "the boot-up and heartbeats went to the handler";
}

TEST_F(SdoClientTest, AbortCodesComeBackWithTheirMeaning) {
  using canopen::sdo_abort::kDeviceState;
  using canopen::sdo_abort::kInvalidValue;
  using canopen::sdo_abort::kLengthMismatch;
  using canopen::sdo_abort::kNoObject;
  using canopen::sdo_abort::kNoSubindex;
  using canopen::sdo_abort::kReadOnly;
  using canopen::sdo_abort::kValueTooHigh;
  EXPECT_EQ(AbortOf([&] { sdo_.Upload(3, 0x2000, 0); },
                    "node 3: SDO read 2000:00 aborted: 0x06020000 (object does not exist in the "
                    "object dictionary)"),
            kNoObject);
  EXPECT_EQ(AbortOf([&] { sdo_.Upload(3, 0x1017, 5); }, "0x06090011 (sub-index does not exist)"),
            kNoSubindex);
  EXPECT_EQ(AbortOf([&] { sdo_.Download(3, cia402::kStatusword, 0, 0, 2); },
                    "node 3: SDO write 6041:00 = 0 aborted: 0x06010002 (attempt to write a "
                    "read-only object)"),
            kReadOnly);
  EXPECT_EQ(AbortOf([&] { sdo_.Download(3, cia402::kModesOfOperation, 0, 3, 1); },
                    "6060:00 = 3 aborted: 0x06090030 (invalid value for parameter)"),
            kInvalidValue);
  EXPECT_EQ(AbortOf([&] { sdo_.Download(3, cia402::kProfileVelocity, 0, 60000, 4); },
                    "0x06090031 (value of parameter written too high)"),
            kValueTooHigh);
  EXPECT_EQ(AbortOf([&] { sdo_.Download(3, cia402::kControlword, 0, 6, 4); },
                    "0x06070010 (data type does not match"),
            kLengthMismatch);
  EXPECT_EQ(AbortOf([&] { sdo_.Download(3, 0x1A00, 1, 0x60640020, 4); },
                    "because of the present device state"),
            kDeviceState)
      << "a mapping changes only while its PDO is invalid";
  EXPECT_EQ(drive_.counters().sdo_aborts, 7);
}

TEST_F(SdoClientTest, PdoMappingFollowsCia301sOrder) {
  using canopen::sdo_abort::kDeviceState;
  using canopen::sdo_abort::kNotMappable;
  const uint32_t cob_id = canopen::kTpdo1Base + 3;
  sdo_.Download(3, 0x1800, 1, canopen::kPdoInvalid | cob_id, 4);
  EXPECT_EQ(AbortOf([&] { sdo_.Download(3, 0x1A00, 1, 0x60640020, 4); }, "device state"),
            kDeviceState)
      << "entries change only while sub 0 is 0";
  sdo_.Download(3, 0x1A00, 0, 0, 1);
  EXPECT_EQ(AbortOf([&] { sdo_.Download(3, 0x1A00, 1, 0x60640010, 4); }, "cannot be mapped"),
            kNotMappable)
      << "6064h is 32 bits, not 16";
  EXPECT_EQ(AbortOf([&] { sdo_.Download(3, 0x1600, 1, 0x60410010, 4); }, "device state"),
            kDeviceState)
      << "RPDO1 is still valid";
  sdo_.Download(3, 0x1A00, 1, 0x60640020, 4);
  sdo_.Download(3, 0x1A00, 0, 1, 1);
  sdo_.Download(3, 0x1800, 1, cob_id, 4);
  EXPECT_EQ(drive_.Object(0x1A00, 0), 1u);
}

TEST_F(SdoClientTest, ASilentNodeIsATimeoutNamingIt) {
  SdoClient quick(*master_, std::chrono::microseconds(30'000), {});
  EXPECT_EQ(AbortOf([&] { quick.Upload(9, 0x1000, 0); },
                    "node 9: SDO read 1000:00: no answer within 30 ms (SDO timeout)"),
            0u);
  EXPECT_EQ(quick.timeouts(), 1);
}

}  // namespace
}  // namespace shapesense
