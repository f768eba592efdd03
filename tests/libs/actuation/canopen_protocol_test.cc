// CANopen encoding (SDO, NMT, EMCY, PDO entries) and the CiA 402 state
// machine: round trips over random values and the invariant that the
// master's walk reaches operation enabled from every state of the drive side.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <random>

#include "libs/actuation/canopen.h"
#include "libs/actuation/cia402.h"

namespace shapesense {
namespace {

using canopen::SdoMessage;
using ::testing::HasSubstr;

TEST(CanopenTest, ExpeditedSdoMessagesRoundTrip) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 1000; ++trial) {
    const uint8_t size = std::array<uint8_t, 3>{1, 2, 4}[rng() % 3];
    const uint32_t mask = size == 4 ? 0xFFFFFFFFu : (1u << (8 * size)) - 1;
    SdoMessage message;
    message.index = static_cast<uint16_t>(rng());
    message.subindex = static_cast<uint8_t>(rng());
    message.value = static_cast<uint32_t>(rng()) & mask;
    message.size = size;
    message.kind = SdoMessage::Kind::kDownloadRequest;
    const SdoMessage request = canopen::ParseSdoRequest(canopen::SdoFrame(0x601, message));
    EXPECT_EQ(request.kind, message.kind);
    EXPECT_EQ(request.index, message.index);
    EXPECT_EQ(request.subindex, message.subindex);
    EXPECT_EQ(request.value, message.value);
    EXPECT_EQ(request.size, size);
    message.kind = SdoMessage::Kind::kUploadResponse;
    const SdoMessage response = canopen::ParseSdoResponse(canopen::SdoFrame(0x581, message));
    EXPECT_EQ(response.kind, message.kind);
    EXPECT_EQ(response.value, message.value);
    EXPECT_EQ(response.size, size);
  }
}

TEST(CanopenTest, SdoCommandBytesAreCia301s) {
  const auto byte0 = [](SdoMessage::Kind kind, uint8_t size) {
    return canopen::SdoFrame(0x601, {kind, 0x6060, 0, 1, size}).data[0];
  };
  EXPECT_EQ(byte0(SdoMessage::Kind::kDownloadRequest, 1), 0x2F);
  EXPECT_EQ(byte0(SdoMessage::Kind::kDownloadRequest, 2), 0x2B);
  EXPECT_EQ(byte0(SdoMessage::Kind::kDownloadRequest, 4), 0x23);
  EXPECT_EQ(byte0(SdoMessage::Kind::kUploadRequest, 0), 0x40);
  EXPECT_EQ(byte0(SdoMessage::Kind::kDownloadResponse, 0), 0x60);
  EXPECT_EQ(byte0(SdoMessage::Kind::kUploadResponse, 2), 0x4B);
  EXPECT_EQ(byte0(SdoMessage::Kind::kAbort, 4), 0x80);
  const CanFrame request =
      canopen::SdoFrame(0x602, {SdoMessage::Kind::kUploadRequest, 0x6064, 0, 0, 0});
  EXPECT_EQ(DescribeFrame(request), "0x602 [8] 40 64 60 00 00 00 00 00");
}

TEST(CanopenTest, AbortsAndSegmentedTransfersAreRecognised) {
  const CanFrame abort = canopen::SdoFrame(
      0x583, {SdoMessage::Kind::kAbort, 0x6081, 0, canopen::sdo_abort::kValueTooHigh, 4});
  const SdoMessage parsed = canopen::ParseSdoResponse(abort);
  EXPECT_EQ(parsed.kind, SdoMessage::Kind::kAbort);
  EXPECT_EQ(parsed.value, 0x06090031u);
  EXPECT_EQ(canopen::SdoAbortText(parsed.value),
            "0x06090031 (value of parameter written too high)");
  EXPECT_THAT(canopen::SdoAbortText(0x12345678), HasSubstr("unknown abort code"));
  CanFrame segmented{
      0x583, 8, {0x41, 0x08, 0x10, 0x00, 20, 0, 0, 0}};  // "upload, size 20, segmented"
  EXPECT_EQ(canopen::ParseSdoResponse(segmented).kind, SdoMessage::Kind::kUnsupported);
  EXPECT_EQ(canopen::ParseSdoResponse(CanFrame{0x583, 4, {0x60}}).kind,
            SdoMessage::Kind::kUnsupported);
}

TEST(CanopenTest, NodeIdsOfFunctionCodes) {
  EXPECT_EQ(canopen::NodeOf(0x705, canopen::kHeartbeatBase), 5);
  EXPECT_EQ(canopen::NodeOf(0x77F, canopen::kHeartbeatBase), 127);
  EXPECT_EQ(canopen::NodeOf(0x080, canopen::kEmcyBase), 0) << "SYNC is no EMCY";
  EXPECT_EQ(canopen::NodeOf(0x181, canopen::kEmcyBase), 0);
  EXPECT_EQ(canopen::NmtFrame(canopen::NmtCommand::kResetCommunication, 3),
            (CanFrame{0x000, 2, {0x82, 3}}));
}

TEST(CanopenTest, EmergenciesAndSignedValues) {
  const CanFrame frame = canopen::EmergencyFrame(4, {0x2310, 0x03});
  EXPECT_EQ(DescribeFrame(frame), "0x084 [8] 10 23 03 00 00 00 00 00");
  EXPECT_EQ(canopen::ParseEmergency(frame).error_code, 0x2310);
  EXPECT_EQ(canopen::DescribeEmergency(0x2310), "0x2310 (current, device output side)");
  EXPECT_EQ(canopen::DescribeEmergency(0x8130), "0x8130 (life guard or heartbeat error)");
  EXPECT_EQ(canopen::DescribeEmergency(0x5530), "0x5530 (device hardware)");
  EXPECT_EQ(canopen::ErrorRegisterFor(0x4210), 0x09);
  std::mt19937 rng(5);
  for (int trial = 0; trial < 1000; ++trial) {
    const int32_t value = static_cast<int32_t>(rng());
    for (size_t bytes : {1u, 2u, 4u}) {
      const int64_t limit = bytes == 4 ? (1ll << 31) : (1ll << (8 * bytes - 1));
      const int32_t small = static_cast<int32_t>(value % limit);
      CanFrame field;
      canopen::PutLittleEndian(&field, 1, bytes, static_cast<uint32_t>(small));
      EXPECT_EQ(canopen::SignExtend(canopen::GetLittleEndian(field, 1, bytes), bytes), small);
    }
  }
}

TEST(CanopenTest, PdoEntriesRoundTrip) {
  const canopen::PdoEntry entry{0x607A, 0, 32};
  EXPECT_EQ(canopen::EncodePdoEntry(entry), 0x607A0020u);
  EXPECT_EQ(canopen::DecodePdoEntry(0x60410010), (canopen::PdoEntry{0x6041, 0, 16}));
}

const cia402::State kStates[] = {cia402::State::kNotReadyToSwitchOn,
                                 cia402::State::kSwitchOnDisabled,
                                 cia402::State::kReadyToSwitchOn,
                                 cia402::State::kSwitchedOn,
                                 cia402::State::kOperationEnabled,
                                 cia402::State::kQuickStopActive,
                                 cia402::State::kFaultReactionActive,
                                 cia402::State::kFault,
                                 cia402::State::kUnknown};

TEST(Cia402Test, EveryStateDecodesFromItsStatusword) {
  std::mt19937 rng(9);
  for (const cia402::State state : kStates) {
    // Bits 7-15 (warning, remote, target reached, ...) never change the state.
    for (int trial = 0; trial < 50; ++trial) {
      const uint16_t other = static_cast<uint16_t>(rng() & 0xFF80);
      EXPECT_EQ(cia402::DecodeStatusword(cia402::StatuswordBits(state) | other), state)
          << cia402::StateName(state);
    }
  }
}

TEST(Cia402Test, TheMastersWalkReachesOperationEnabledFromEveryState) {
  for (const cia402::State start : kStates) {
    if (start == cia402::State::kNotReadyToSwitchOn ||
        start == cia402::State::kFaultReactionActive) {
      continue;  // transient: the drive leaves them by itself
    }
    cia402::State state = start;
    uint16_t previous = 0;
    int steps = 0;
    for (; state != cia402::State::kOperationEnabled && steps < 5; ++steps) {
      const std::optional<uint16_t> controlword = cia402::ControlwordTowardOperationEnabled(state);
      ASSERT_TRUE(controlword) << cia402::StateName(state);
      state = cia402::NextState(state, *controlword, previous);
      previous = *controlword;
    }
    EXPECT_EQ(state, cia402::State::kOperationEnabled) << "from " << cia402::StateName(start);
    EXPECT_LE(steps, 4);
  }
}

TEST(Cia402Test, DriveSideTransitions) {
  namespace cw = cia402::controlword;
  using S = cia402::State;
  EXPECT_EQ(cia402::NextState(S::kOperationEnabled, cw::kQuickStop, cw::kEnableOperation),
            S::kQuickStopActive);
  EXPECT_EQ(cia402::NextState(S::kOperationEnabled, cw::kEnableOperation | cw::kHalt, 0),
            S::kOperationEnabled);
  EXPECT_EQ(cia402::NextState(S::kFault, cw::kFaultReset, cw::kFaultReset), S::kFault)
      << "a fault reset acts on the rising edge only";
  EXPECT_EQ(cia402::NextState(S::kFault, cw::kFaultReset, 0), S::kSwitchOnDisabled);
  EXPECT_EQ(cia402::NextState(S::kSwitchOnDisabled, cw::kEnableOperation, 0), S::kSwitchOnDisabled)
      << "no short cut past ready to switch on";
  EXPECT_EQ(cia402::NextState(S::kSwitchedOn, cw::kDisableVoltage, 0), S::kSwitchOnDisabled);
}

}  // namespace
}  // namespace shapesense
