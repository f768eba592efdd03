#include "libs/actuation/canopen.h"

#include <cstdio>
#include <map>

namespace shapesense::canopen {
namespace {

std::string Hex(uint32_t value, int digits) {
  char text[16];
  std::snprintf(text, sizeof(text), "0x%0*X", digits, value);
  return text;
}

// The low nibble of an expedited SDO command byte: n (unused bytes) and the e and s bits.
uint8_t ExpeditedBits(uint8_t size) {
  if (size == 0) return 0x02;  // expedited, size not indicated
  return static_cast<uint8_t>(((4 - size) << 2) | 0x03);
}

uint8_t ExpeditedSize(uint8_t command) {
  return (command & 0x01) ? static_cast<uint8_t>(4 - ((command >> 2) & 0x03)) : 0;
}

SdoMessage Addressed(const CanFrame& frame, SdoMessage::Kind kind) {
  SdoMessage message;
  message.kind = kind;
  message.index = static_cast<uint16_t>(GetLittleEndian(frame, 1, 2));
  message.subindex = frame.data[3];
  return message;
}

// What an expedited transfer carries; segmented ones are not supported.
SdoMessage WithData(const CanFrame& frame, SdoMessage::Kind kind) {
  const uint8_t command = frame.data[0];
  if (!(command & 0x02)) return Addressed(frame, SdoMessage::Kind::kUnsupported);
  SdoMessage message = Addressed(frame, kind);
  message.size = ExpeditedSize(command);
  message.value = GetLittleEndian(frame, 4, message.size == 0 ? 4 : message.size);
  return message;
}

}  // namespace

std::string NmtStateName(uint8_t state) {
  switch (static_cast<NmtState>(state)) {
    case NmtState::kBootUp:
      return "boot-up";
    case NmtState::kStopped:
      return "stopped";
    case NmtState::kOperational:
      return "operational";
    case NmtState::kPreOperational:
      return "pre-operational";
  }
  return Hex(state, 2);
}

int NodeOf(uint32_t id, uint32_t base) {
  return id > base && id - base <= 127 ? static_cast<int>(id - base) : 0;
}

CanFrame NmtFrame(NmtCommand command, int node) {
  return {kNmtId, 2, {static_cast<uint8_t>(command), static_cast<uint8_t>(node)}};
}

CanFrame SyncFrame() { return {kSyncId, 0, {}}; }

CanFrame HeartbeatFrame(int node, NmtState state) {
  return {kHeartbeatBase + static_cast<uint32_t>(node), 1, {static_cast<uint8_t>(state)}};
}

CanFrame EmergencyFrame(int node, const Emergency& emergency) {
  CanFrame frame{kEmcyBase + static_cast<uint32_t>(node), 8, {}};
  PutLittleEndian(&frame, 0, 2, emergency.error_code);
  frame.data[2] = emergency.error_register;
  return frame;
}

Emergency ParseEmergency(const CanFrame& frame) {
  Emergency emergency;
  emergency.error_code = static_cast<uint16_t>(GetLittleEndian(frame, 0, 2));
  emergency.error_register = frame.size > 2 ? frame.data[2] : 0;
  return emergency;
}

std::string DescribeEmergency(uint16_t code) {
  static const std::map<uint16_t, const char*> kKnown = {
      {0x0000, "error reset"},
      {0x8110, "CAN overrun"},
      {0x8120, "CAN in error passive"},
      {0x8130, "life guard or heartbeat error"},
      {0x8140, "recovered from bus-off"},
      {0x8210, "PDO not processed: length error"},
      {0x8611, "following error"},
  };
  static const std::map<uint16_t, const char*> kClasses = {
      {0x1000, "generic error"},
      {0x2100, "current, device input side"},
      {0x2200, "current inside the device"},
      {0x2300, "current, device output side"},
      {0x3100, "mains voltage"},
      {0x3200, "voltage inside the device"},
      {0x3300, "output voltage"},
      {0x4100, "ambient temperature"},
      {0x4200, "device temperature"},
      {0x5000, "device hardware"},
      {0x6100, "internal software"},
      {0x6200, "user software"},
      {0x6300, "data set"},
      {0x7000, "additional modules"},
      {0x8100, "communication"},
      {0x8200, "protocol error"},
      {0x8000, "monitoring"},
      {0x9000, "external error"},
      {0xF000, "additional functions"},
      {0xFF00, "device specific"},
  };
  const char* what = "unknown error class";
  if (const auto known = kKnown.find(code); known != kKnown.end()) {
    what = known->second;
  } else if (const auto group = kClasses.find(code & 0xFF00); group != kClasses.end()) {
    what = group->second;
  } else if (const auto family = kClasses.find(code & 0xF000); family != kClasses.end()) {
    what = family->second;
  }
  return Hex(code, 4) + " (" + what + ")";
}

uint8_t ErrorRegisterFor(uint16_t code) {
  if (code == 0) return 0;
  switch (code >> 12) {
    case 0x2:
      return 0x03;  // generic + current
    case 0x3:
      return 0x05;  // generic + voltage
    case 0x4:
      return 0x09;  // generic + temperature
    case 0x8:
      return 0x11;  // generic + communication
    default:
      return 0x01;
  }
}

CanFrame SdoFrame(uint32_t cob_id, const SdoMessage& message) {
  using Kind = SdoMessage::Kind;
  CanFrame frame{cob_id, 8, {}};
  PutLittleEndian(&frame, 1, 2, message.index);
  frame.data[3] = message.subindex;
  switch (message.kind) {
    case Kind::kDownloadRequest:
      frame.data[0] = static_cast<uint8_t>(0x20 | ExpeditedBits(message.size));
      break;
    case Kind::kDownloadResponse:
      frame.data[0] = 0x60;
      return frame;
    case Kind::kUploadRequest:
      frame.data[0] = 0x40;
      return frame;
    case Kind::kUploadResponse:
      frame.data[0] = static_cast<uint8_t>(0x40 | ExpeditedBits(message.size));
      break;
    case Kind::kAbort:
      frame.data[0] = 0x80;
      break;
    case Kind::kUnsupported:
      return frame;
  }
  PutLittleEndian(&frame, 4, message.size == 0 ? 4 : message.size, message.value);
  return frame;
}

namespace {

// An abort looks the same in both directions: the address and a 4-byte code.
SdoMessage ParseSdoAbort(const CanFrame& frame) {
  SdoMessage abort = Addressed(frame, SdoMessage::Kind::kAbort);
  abort.value = GetLittleEndian(frame, 4, 4);
  return abort;
}

}  // namespace

SdoMessage ParseSdoRequest(const CanFrame& frame) {
  using Kind = SdoMessage::Kind;
  if (frame.size != 8) return {};
  switch (frame.data[0] >> 5) {
    case 1:
      return WithData(frame, Kind::kDownloadRequest);
    case 2:
      return Addressed(frame, Kind::kUploadRequest);
    case 4:
      return ParseSdoAbort(frame);
    default:
      return {};
  }
}

SdoMessage ParseSdoResponse(const CanFrame& frame) {
  using Kind = SdoMessage::Kind;
  if (frame.size != 8) return {};
  switch (frame.data[0] >> 5) {
    case 3:
      return Addressed(frame, Kind::kDownloadResponse);
    case 2:
      return WithData(frame, Kind::kUploadResponse);
    case 4:
      return ParseSdoAbort(frame);
    default:
      return {};
  }
}

std::string SdoAbortText(uint32_t code) {
  static const std::map<uint32_t, const char*> kTexts = {
      {0x05030000, "toggle bit not alternated"},
      {0x05040000, "SDO protocol timed out"},
      {0x05040001, "client/server command specifier not valid or unknown"},
      {0x05040005, "out of memory"},
      {0x06010000, "unsupported access to an object"},
      {0x06010001, "attempt to read a write-only object"},
      {0x06010002, "attempt to write a read-only object"},
      {0x06020000, "object does not exist in the object dictionary"},
      {0x06040041, "object cannot be mapped to the PDO"},
      {0x06040042, "the objects to be mapped would exceed the PDO length"},
      {0x06040043, "general parameter incompatibility"},
      {0x06040047, "general internal incompatibility in the device"},
      {0x06060000, "access failed due to a hardware error"},
      {0x06070010, "data type does not match: length of service parameter does not match"},
      {0x06070012, "data type does not match: length of service parameter too high"},
      {0x06070013, "data type does not match: length of service parameter too low"},
      {0x06090011, "sub-index does not exist"},
      {0x06090030, "invalid value for parameter"},
      {0x06090031, "value of parameter written too high"},
      {0x06090032, "value of parameter written too low"},
      {0x06090036, "maximum value is less than minimum value"},
      {0x060A0023, "resource not available: SDO connection"},
      {0x08000000, "general error"},
      {0x08000020, "data cannot be transferred or stored to the application"},
      {0x08000021, "data cannot be transferred or stored because of local control"},
      {0x08000022, "data cannot be transferred or stored because of the present device state"},
      {0x08000023, "no object dictionary is present"},
  };
  const auto it = kTexts.find(code);
  return Hex(code, 8) + " (" + (it == kTexts.end() ? "unknown abort code" : it->second) + ")";
}

uint32_t GetLittleEndian(const CanFrame& frame, size_t offset, size_t bytes) {
  uint32_t value = 0;
  for (size_t i = 0; i < bytes && offset + i < frame.data.size(); ++i) {
    value |= static_cast<uint32_t>(frame.data[offset + i]) << (8 * i);
  }
  return value;
}

void PutLittleEndian(CanFrame* frame, size_t offset, size_t bytes, uint32_t value) {
  for (size_t i = 0; i < bytes && offset + i < frame->data.size(); ++i) {
    frame->data[offset + i] = static_cast<uint8_t>(value >> (8 * i));
  }
}

int32_t SignExtend(uint32_t value, size_t bytes) {
  if (bytes == 0) return 0;
  if (bytes >= 4) return static_cast<int32_t>(value);
  const uint32_t sign = 1u << (8 * bytes - 1);
  const uint32_t mask = (1u << (8 * bytes)) - 1;
  value &= mask;
  return static_cast<int32_t>(value ^ sign) - static_cast<int32_t>(sign);
}

}  // namespace shapesense::canopen
