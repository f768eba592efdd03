#include "libs/actuation/cia402.h"

namespace shapesense::cia402 {
namespace {

enum class Command { kDisableVoltage, kQuickStop, kShutdown, kSwitchOn, kEnableOperation };

// The command of bits 0-3 (CiA 402 table "device control commands").
Command DecodeCommand(uint16_t controlword) {
  if (!(controlword & 0x0002)) return Command::kDisableVoltage;
  if (!(controlword & 0x0004)) return Command::kQuickStop;
  if (!(controlword & 0x0001)) return Command::kShutdown;
  if (!(controlword & 0x0008)) return Command::kSwitchOn;
  return Command::kEnableOperation;
}

State FromReadyToSwitchOn(Command command) {
  switch (command) {
    case Command::kSwitchOn:
      return State::kSwitchedOn;
    case Command::kEnableOperation:
      return State::kOperationEnabled;  // transitions 3 and 4 at once, as drives allow
    case Command::kShutdown:
      return State::kReadyToSwitchOn;
    default:
      return State::kSwitchOnDisabled;
  }
}

State FromSwitchedOn(Command command) {
  switch (command) {
    case Command::kEnableOperation:
      return State::kOperationEnabled;
    case Command::kShutdown:
      return State::kReadyToSwitchOn;
    case Command::kSwitchOn:
      return State::kSwitchedOn;
    default:
      return State::kSwitchOnDisabled;
  }
}

State FromOperationEnabled(Command command) {
  switch (command) {
    case Command::kEnableOperation:
      return State::kOperationEnabled;
    case Command::kSwitchOn:
      return State::kSwitchedOn;
    case Command::kShutdown:
      return State::kReadyToSwitchOn;
    case Command::kQuickStop:
      return State::kQuickStopActive;
    case Command::kDisableVoltage:
      return State::kSwitchOnDisabled;
  }
  return State::kOperationEnabled;
}

}  // namespace

const char* StateName(State state) {
  switch (state) {
    case State::kNotReadyToSwitchOn:
      return "not ready to switch on";
    case State::kSwitchOnDisabled:
      return "switch on disabled";
    case State::kReadyToSwitchOn:
      return "ready to switch on";
    case State::kSwitchedOn:
      return "switched on";
    case State::kOperationEnabled:
      return "operation enabled";
    case State::kQuickStopActive:
      return "quick stop active";
    case State::kFaultReactionActive:
      return "fault reaction active";
    case State::kFault:
      return "fault";
    case State::kUnknown:
      return "unknown";
  }
  return "unknown";
}

State DecodeStatusword(uint16_t statusword) {
  switch (statusword & 0x4F) {
    case 0x00:
      return State::kNotReadyToSwitchOn;
    case 0x40:
      return State::kSwitchOnDisabled;
    case 0x0F:
      return State::kFaultReactionActive;
    case 0x08:
      return State::kFault;
    default:
      break;
  }
  switch (statusword & 0x6F) {
    case 0x21:
      return State::kReadyToSwitchOn;
    case 0x23:
      return State::kSwitchedOn;
    case 0x27:
      return State::kOperationEnabled;
    case 0x07:
      return State::kQuickStopActive;
    default:
      return State::kUnknown;
  }
}

uint16_t StatuswordBits(State state) {
  switch (state) {
    case State::kNotReadyToSwitchOn:
      return 0x0000;
    case State::kSwitchOnDisabled:
      return 0x0040;
    case State::kReadyToSwitchOn:
      return 0x0021 | statusword::kVoltageEnabled;
    case State::kSwitchedOn:
      return 0x0023 | statusword::kVoltageEnabled;
    case State::kOperationEnabled:
      return 0x0027 | statusword::kVoltageEnabled;
    case State::kQuickStopActive:
      return 0x0007 | statusword::kVoltageEnabled;
    case State::kFaultReactionActive:
      return 0x000F;
    case State::kFault:
      return 0x0008;
    case State::kUnknown:
      return 0x0001;  // "ready to switch on" without the quick stop bit: no state
  }
  return 0x0001;
}

State NextState(State state, uint16_t controlword, uint16_t previous) {
  const Command command = DecodeCommand(controlword);
  switch (state) {
    case State::kFault: {
      const bool reset_edge =
          (controlword & controlword::kFaultReset) && !(previous & controlword::kFaultReset);
      return reset_edge ? State::kSwitchOnDisabled : State::kFault;
    }
    case State::kSwitchOnDisabled:
      return command == Command::kShutdown ? State::kReadyToSwitchOn : state;
    case State::kReadyToSwitchOn:
      return FromReadyToSwitchOn(command);
    case State::kSwitchedOn:
      return FromSwitchedOn(command);
    case State::kOperationEnabled:
      return FromOperationEnabled(command);
    case State::kQuickStopActive:
      if (command == Command::kDisableVoltage) return State::kSwitchOnDisabled;
      return command == Command::kEnableOperation ? State::kOperationEnabled : state;
    case State::kUnknown:
      // A statusword the master cannot read: disable voltage is safe from any state.
      return command == Command::kDisableVoltage ? State::kSwitchOnDisabled : state;
    default:
      return state;  // transient: the drive leaves these by itself
  }
}

std::optional<uint16_t> ControlwordTowardOperationEnabled(State state) {
  switch (state) {
    case State::kSwitchOnDisabled:
      return controlword::kShutdown;
    case State::kReadyToSwitchOn:
      return controlword::kSwitchOn;
    case State::kSwitchedOn:
      return controlword::kEnableOperation;
    case State::kQuickStopActive:
    case State::kUnknown:
      return controlword::kDisableVoltage;
    case State::kFault:
      return controlword::kFaultReset;
    default:
      return std::nullopt;
  }
}

}  // namespace shapesense::cia402
