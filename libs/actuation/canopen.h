#pragma once

// CANopen (CiA 301) as far as a CiA 402 master and its simulated drives need
// it: the predefined connection set's COB-IDs, NMT, SYNC, heartbeat, EMCY,
// expedited SDO and PDO mapping entries. Pure encoding and decoding.

#include <cstdint>
#include <optional>
#include <string>

#include "libs/actuation/can_bus.h"

namespace shapesense::canopen {

// Function codes of the predefined connection set (COB-ID = base + node id).
constexpr uint32_t kNmtId = 0x000;
constexpr uint32_t kSyncId = 0x080;
constexpr uint32_t kEmcyBase = 0x080;
constexpr uint32_t kTpdo1Base = 0x180;
constexpr uint32_t kRpdo1Base = 0x200;
constexpr uint32_t kSdoResponseBase = 0x580;  // server (drive) → client (master)
constexpr uint32_t kSdoRequestBase = 0x600;   // client → server
constexpr uint32_t kHeartbeatBase = 0x700;
// Bit 31 of a PDO's COB-ID entry: the PDO does not exist (is disabled).
constexpr uint32_t kPdoInvalid = 0x80000000u;

enum class NmtCommand : uint8_t {
  kStart = 0x01,
  kStop = 0x02,
  kEnterPreOperational = 0x80,
  kResetNode = 0x81,
  kResetCommunication = 0x82,
};

enum class NmtState : uint8_t {
  kBootUp = 0x00,
  kStopped = 0x04,
  kOperational = 0x05,
  kPreOperational = 0x7F,
};
// "operational", "pre-operational", ... or "0xNN".
std::string NmtStateName(uint8_t state);

// The node id of a frame with `base` (e.g. kHeartbeatBase), or 0 when the id
// is not base + 1..127.
int NodeOf(uint32_t id, uint32_t base);

CanFrame NmtFrame(NmtCommand command, int node);  // node 0: every node
CanFrame SyncFrame();
CanFrame HeartbeatFrame(int node, NmtState state);

// Emergency: the error code (CiA 301 / CiA 402 table), the error register (1001h).
struct Emergency {
  uint16_t error_code = 0;
  uint8_t error_register = 0;
};
CanFrame EmergencyFrame(int node, const Emergency& emergency);
Emergency ParseEmergency(const CanFrame& frame);
// "0x2310 (current, device output side)"; error code 0 is "error reset".
std::string DescribeEmergency(uint16_t error_code);
// The error register bits a code sets: bit 0 generic always, then current,
// voltage, temperature or communication by the code's class.
uint8_t ErrorRegisterFor(uint16_t error_code);

// Expedited SDO (values of up to 4 bytes): the only kind this master needs.
struct SdoMessage {
  enum class Kind {
    kDownloadRequest,   // client writes `value` (`size` bytes; 0: size not given)
    kDownloadResponse,  // server confirms a write
    kUploadRequest,     // client reads
    kUploadResponse,    // server answers a read with `value` (`size` bytes)
    kAbort,             // either side: `value` is the abort code
    kUnsupported,       // segmented or block transfers, anything else
  };
  Kind kind = Kind::kUnsupported;
  uint16_t index = 0;
  uint8_t subindex = 0;
  uint32_t value = 0;
  uint8_t size = 0;
};
// Requests go to base kSdoRequestBase, responses come from kSdoResponseBase.
CanFrame SdoFrame(uint32_t cob_id, const SdoMessage& message);
SdoMessage ParseSdoRequest(const CanFrame& frame);
SdoMessage ParseSdoResponse(const CanFrame& frame);
// "object does not exist in the object dictionary", ... (CiA 301 table).
std::string SdoAbortText(uint32_t code);

// SDO abort codes the simulated drive uses.
namespace sdo_abort {
constexpr uint32_t kTimeout = 0x05040000;
constexpr uint32_t kUnknownCommand = 0x05040001;
constexpr uint32_t kWriteOnly = 0x06010001;
constexpr uint32_t kReadOnly = 0x06010002;
constexpr uint32_t kNoObject = 0x06020000;
constexpr uint32_t kNotMappable = 0x06040041;
constexpr uint32_t kPdoTooLong = 0x06040042;
constexpr uint32_t kLengthMismatch = 0x06070010;
constexpr uint32_t kNoSubindex = 0x06090011;
constexpr uint32_t kInvalidValue = 0x06090030;
constexpr uint32_t kValueTooHigh = 0x06090031;
constexpr uint32_t kValueTooLow = 0x06090032;
constexpr uint32_t kDeviceState = 0x08000022;
}  // namespace sdo_abort

// A PDO mapping entry: object index, subindex and length in bits.
struct PdoEntry {
  uint16_t index = 0;
  uint8_t subindex = 0;
  uint8_t bits = 0;
  bool operator==(const PdoEntry&) const = default;
};
constexpr uint32_t EncodePdoEntry(const PdoEntry& entry) {
  return (static_cast<uint32_t>(entry.index) << 16) | (static_cast<uint32_t>(entry.subindex) << 8) |
         entry.bits;
}
constexpr PdoEntry DecodePdoEntry(uint32_t value) {
  return {static_cast<uint16_t>(value >> 16), static_cast<uint8_t>(value >> 8),
          static_cast<uint8_t>(value)};
}

// Little-endian field access into frame data (CANopen's byte order).
uint32_t GetLittleEndian(const CanFrame& frame, size_t offset, size_t bytes);
void PutLittleEndian(CanFrame* frame, size_t offset, size_t bytes, uint32_t value);
// The value of `bytes` bytes read as a signed integer.
int32_t SignExtend(uint32_t value, size_t bytes);

}  // namespace shapesense::canopen
