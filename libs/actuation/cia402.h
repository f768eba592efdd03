#pragma once

// CiA 402 (drives and motion control): the power state machine as the
// statusword shows it and the controlword drives it, and the profile-position
// bits. Pure functions; the master walks a drive to operation enabled with
// them and the simulated drive implements the other side with them.

#include <cstdint>
#include <optional>

namespace shapesense::cia402 {

// Objects of the drive profile (index; subindex 0).
constexpr uint16_t kErrorCode = 0x603F;
constexpr uint16_t kControlword = 0x6040;
constexpr uint16_t kStatusword = 0x6041;
constexpr uint16_t kModesOfOperation = 0x6060;
constexpr uint16_t kModesOfOperationDisplay = 0x6061;
constexpr uint16_t kPositionActual = 0x6064;
constexpr uint16_t kPositionWindow = 0x6067;
constexpr uint16_t kTargetPosition = 0x607A;
constexpr uint16_t kProfileVelocity = 0x6081;
constexpr uint16_t kProfileAcceleration = 0x6083;
constexpr uint16_t kProfileDeceleration = 0x6084;
constexpr uint16_t kQuickStopDeceleration = 0x6085;
constexpr int8_t kProfilePositionMode = 1;
// 1000h's low 16 bits for a drive of this profile.
constexpr uint32_t kDeviceProfile = 402;

// Controlword commands (bits 0-3 and 7) and profile-position bits.
namespace controlword {
constexpr uint16_t kShutdown = 0x0006;
constexpr uint16_t kSwitchOn = 0x0007;  // also "disable operation"
constexpr uint16_t kEnableOperation = 0x000F;
constexpr uint16_t kDisableVoltage = 0x0000;
constexpr uint16_t kQuickStop = 0x0002;
constexpr uint16_t kFaultReset = 0x0080;  // on its rising edge
constexpr uint16_t kNewSetpoint = 0x0010;
constexpr uint16_t kChangeSetImmediately = 0x0020;
constexpr uint16_t kRelative = 0x0040;
constexpr uint16_t kHalt = 0x0100;
}  // namespace controlword

namespace statusword {
constexpr uint16_t kFault = 0x0008;
constexpr uint16_t kVoltageEnabled = 0x0010;
constexpr uint16_t kWarning = 0x0080;
constexpr uint16_t kRemote = 0x0200;
constexpr uint16_t kTargetReached = 0x0400;
constexpr uint16_t kSetpointAcknowledge = 0x1000;
constexpr uint16_t kFollowingError = 0x2000;
}  // namespace statusword

enum class State {
  kNotReadyToSwitchOn,
  kSwitchOnDisabled,
  kReadyToSwitchOn,
  kSwitchedOn,
  kOperationEnabled,
  kQuickStopActive,
  kFaultReactionActive,
  kFault,
  kUnknown,  // a statusword that is none of the above
};

const char* StateName(State state);
State DecodeStatusword(uint16_t statusword);
// The state bits of a statusword (bits 0-6) a drive in `state` shows.
uint16_t StatuswordBits(State state);

// The drive side: the state `controlword` takes a drive in `state` to
// (`previous` is the controlword before, for the fault reset's rising edge).
// Transient states (not ready, fault reaction) are left by the drive itself.
State NextState(State state, uint16_t controlword, uint16_t previous);

// The master side: the controlword that takes a drive one step toward
// operation enabled; nullopt when it is there or must be waited for. From a
// fault it is kFaultReset, which acts on a rising edge: write kDisableVoltage
// first.
std::optional<uint16_t> ControlwordTowardOperationEnabled(State state);

}  // namespace shapesense::cia402
