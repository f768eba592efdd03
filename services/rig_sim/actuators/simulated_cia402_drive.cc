#include "services/rig_sim/actuators/simulated_cia402_drive.h"

#include <cmath>
#include <vector>

#include "runtime/devices/device_clock.h"

namespace shapesense {
namespace {

using canopen::NmtState;
using canopen::PdoEntry;
using canopen::SdoMessage;
using Access = OdEntry::Access;

constexpr uint16_t kDeviceType = 0x1000;
constexpr uint16_t kErrorRegister = 0x1001;
constexpr uint16_t kHeartbeatTime = 0x1017;
constexpr uint16_t kRpdo1Communication = 0x1400;
constexpr uint16_t kRpdo1Mapping = 0x1600;
constexpr uint16_t kTpdo1Communication = 0x1800;
constexpr uint16_t kTpdo1Mapping = 0x1A00;
constexpr uint16_t kPdoLengthError = 0x8210;
constexpr auto kReceiveTimeout = std::chrono::microseconds(2000);

OdEntry Unsigned(uint8_t size, Access access, uint32_t default_value, bool mappable = false) {
  OdEntry entry;
  entry.size = size;
  entry.access = access;
  entry.default_value = default_value;
  entry.max = size == 4 ? 0xFFFFFFFFll : (1ll << (8 * size)) - 1;
  entry.mappable = mappable;
  return entry;
}

OdEntry Signed(uint8_t size, Access access, int32_t default_value, bool mappable = false) {
  OdEntry entry;
  entry.size = size;
  entry.is_signed = true;
  entry.access = access;
  entry.default_value = static_cast<uint32_t>(default_value);
  entry.min = -(1ll << (8 * size - 1));
  entry.max = (1ll << (8 * size - 1)) - 1;
  entry.mappable = mappable;
  return entry;
}

void AddCommunicationObjects(ObjectDictionary& od, const SimulatedDriveOptions& options) {
  const uint32_t node = static_cast<uint32_t>(options.node_id);
  od.Add(kDeviceType, 0, Unsigned(4, Access::kReadOnly, options.device_type));
  od.Add(kErrorRegister, 0, Unsigned(1, Access::kReadOnly, 0));
  od.Add(kHeartbeatTime, 0, Unsigned(2, Access::kReadWrite, 0));
  // PDO 1 as the drive leaves the factory: RPDO1 = controlword + target
  // position (applied on receipt), TPDO1 = statusword + actual position (every SYNC).
  od.Add(kRpdo1Communication, 1, Unsigned(4, Access::kReadWrite, canopen::kRpdo1Base + node));
  od.Add(kRpdo1Communication, 2, Unsigned(1, Access::kReadWrite, 0xFF));
  od.Add(kTpdo1Communication, 1, Unsigned(4, Access::kReadWrite, canopen::kTpdo1Base + node));
  od.Add(kTpdo1Communication, 2, Unsigned(1, Access::kReadWrite, 1));
  const uint32_t rpdo_defaults[] = {0x60400010, 0x607A0020};
  const uint32_t tpdo_defaults[] = {0x60410010, 0x60640020};
  od.Add(kRpdo1Mapping, 0, Unsigned(1, Access::kReadWrite, 2));
  od.Add(kTpdo1Mapping, 0, Unsigned(1, Access::kReadWrite, 2));
  for (uint8_t sub = 1; sub <= 8; ++sub) {
    od.Add(kRpdo1Mapping, sub,
           Unsigned(4, Access::kReadWrite, sub <= 2 ? rpdo_defaults[sub - 1] : 0));
    od.Add(kTpdo1Mapping, sub,
           Unsigned(4, Access::kReadWrite, sub <= 2 ? tpdo_defaults[sub - 1] : 0));
  }
}

void AddDriveObjects(ObjectDictionary& od, const SimulatedDriveOptions& options) {
  od.Add(cia402::kErrorCode, 0, Unsigned(2, Access::kReadOnly, 0, true));
  od.Add(cia402::kControlword, 0, Unsigned(2, Access::kReadWrite, 0, true));
  od.Add(cia402::kStatusword, 0, Unsigned(2, Access::kReadOnly, 0, true));
  OdEntry mode = Signed(1, Access::kReadWrite, 0, true);
  mode.allowed = {cia402::kProfilePositionMode};  // the only mode this drive has
  od.Add(cia402::kModesOfOperation, 0, mode);
  od.Add(cia402::kModesOfOperationDisplay, 0, Signed(1, Access::kReadOnly, 0, true));
  od.Add(cia402::kPositionActual, 0, Signed(4, Access::kReadOnly, options.initial_position, true));
  od.Add(cia402::kPositionWindow, 0, Unsigned(4, Access::kReadWrite, 10));
  od.Add(cia402::kTargetPosition, 0, Signed(4, Access::kReadWrite, 0, true));
  OdEntry velocity = Unsigned(4, Access::kReadWrite, 10000);
  velocity.min = 1;
  velocity.max = static_cast<int64_t>(options.max_velocity_counts_s);
  od.Add(cia402::kProfileVelocity, 0, velocity);
  OdEntry rate = Unsigned(4, Access::kReadWrite, 100000);
  rate.min = 1;
  for (const uint16_t index : {cia402::kProfileAcceleration, cia402::kProfileDeceleration,
                               cia402::kQuickStopDeceleration}) {
    od.Add(index, 0, rate);
  }
}

}  // namespace

SimulatedCia402Drive::SimulatedCia402Drive(std::unique_ptr<CanBus> bus,
                                           SimulatedDriveOptions options)
    : options_(options), bus_(std::move(bus)) {
  AddCommunicationObjects(od_, options_);
  AddDriveObjects(od_, options_);
  motion_.position = motion_.target = options_.initial_position;
}

SimulatedCia402Drive::~SimulatedCia402Drive() { PowerOff(); }

void SimulatedCia402Drive::PowerOn() {
  if (running_) return;
  {
    std::lock_guard lock(mutex_);
    BootLocked(/*reset_application=*/true);
  }
  running_ = true;
  thread_ = std::thread([this] { Serve(); });
}

void SimulatedCia402Drive::PowerOff() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
}

void SimulatedCia402Drive::InjectFault(uint16_t error_code) {
  std::lock_guard lock(mutex_);
  pending_fault_ = error_code;
}

void SimulatedCia402Drive::Serve() {
  while (running_) ServeOnce();
}

void SimulatedCia402Drive::ServeOnce() {
  std::optional<CanFrame> frame;
  try {
    frame = bus_->Receive(kReceiveTimeout);
  } catch (const CanBusError&) {
    std::this_thread::sleep_for(kReceiveTimeout);  // the cable is cut: nothing to hear
  }
  std::lock_guard lock(mutex_);
  const int64_t now_us = SteadyMicros();
  AdvanceLocked(now_us);
  if (pending_fault_) {
    EnterFaultLocked(*pending_fault_);
    pending_fault_.reset();
  }
  if (frame) HandleLocked(*frame);
  HeartbeatLocked(now_us);
}

void SimulatedCia402Drive::BootLocked(bool reset_application) {
  if (reset_application) {
    od_.ResetRange(0x2000, 0xFFFF);
    state_ = cia402::State::kSwitchOnDisabled;  // "not ready" passes at once
    previous_controlword_ = 0;
    setpoint_acknowledged_ = false;
    motion_.Hold();
  }
  od_.ResetRange(0x1000, 0x1FFF);
  pending_rpdo_.reset();
  sync_count_ = 0;
  last_advance_us_ = SteadyMicros();
  next_heartbeat_us_ = 0;
  UpdateStatuswordLocked();
  SendLocked(canopen::HeartbeatFrame(options_.node_id, NmtState::kBootUp));
  nmt_ = static_cast<uint8_t>(NmtState::kPreOperational);
}

void SimulatedCia402Drive::HandleLocked(const CanFrame& frame) {
  const uint32_t node = static_cast<uint32_t>(options_.node_id);
  if (frame.id == canopen::kNmtId) {
    HandleNmtLocked(frame);
  } else if (frame.id == canopen::kSyncId) {
    HandleSyncLocked();
  } else if (frame.id == canopen::kSdoRequestBase + node) {
    HandleSdoLocked(frame);
  } else if (PdoValidLocked(kRpdo1Communication) &&
             frame.id == (od_.Get(kRpdo1Communication, 1) & 0x7FF)) {
    HandleRpdoLocked(frame);
  }
}

void SimulatedCia402Drive::HandleNmtLocked(const CanFrame& frame) {
  if (frame.size < 2 || (frame.data[1] != 0 && frame.data[1] != options_.node_id)) return;
  switch (static_cast<canopen::NmtCommand>(frame.data[0])) {
    case canopen::NmtCommand::kStart:
      nmt_ = static_cast<uint8_t>(NmtState::kOperational);
      break;
    case canopen::NmtCommand::kStop:
      nmt_ = static_cast<uint8_t>(NmtState::kStopped);
      break;
    case canopen::NmtCommand::kEnterPreOperational:
      nmt_ = static_cast<uint8_t>(NmtState::kPreOperational);
      break;
    case canopen::NmtCommand::kResetNode:
      BootLocked(/*reset_application=*/true);
      break;
    case canopen::NmtCommand::kResetCommunication:
      BootLocked(/*reset_application=*/false);
      break;
  }
}

void SimulatedCia402Drive::HandleSyncLocked() {
  if (nmt_ != static_cast<uint8_t>(NmtState::kOperational)) return;
  if (pending_rpdo_) {
    const CanFrame rpdo = *pending_rpdo_;
    pending_rpdo_.reset();
    ApplyRpdoLocked(rpdo);
  }
  ++sync_count_;
  const uint32_t type = od_.Get(kTpdo1Communication, 2);
  const uint32_t every = type == 0 ? 1 : type;
  if (PdoValidLocked(kTpdo1Communication) && every <= 240 && sync_count_ % every == 0) {
    SendTpdoLocked();
  }
}

void SimulatedCia402Drive::HandleSdoLocked(const CanFrame& frame) {
  if (nmt_ == static_cast<uint8_t>(NmtState::kStopped)) return;
  const SdoMessage request = canopen::ParseSdoRequest(frame);
  const uint32_t reply_id = canopen::kSdoResponseBase + static_cast<uint32_t>(options_.node_id);
  SdoMessage reply{SdoMessage::Kind::kAbort, request.index, request.subindex, 0, 4};
  if (request.kind == SdoMessage::Kind::kAbort) return;
  if (request.kind == SdoMessage::Kind::kUploadRequest) {
    uint32_t value = 0;
    uint8_t size = 0;
    reply.value = od_.Read(request.index, request.subindex, &value, &size);
    if (reply.value == 0) {
      reply = {SdoMessage::Kind::kUploadResponse, request.index, request.subindex, value, size};
    }
  } else if (request.kind == SdoMessage::Kind::kDownloadRequest) {
    reply.value = CheckPdoConfigWriteLocked(request.index, request.subindex, request.value);
    if (reply.value == 0) {
      reply.value = od_.Write(request.index, request.subindex, request.value, request.size);
    }
    if (reply.value == 0) {
      reply.kind = SdoMessage::Kind::kDownloadResponse;
      if (request.index == cia402::kControlword) ProcessControlwordLocked();
      if (request.index == cia402::kModesOfOperation) {
        od_.Set(cia402::kModesOfOperationDisplay, 0, od_.Get(cia402::kModesOfOperation, 0));
      }
      if (request.index == kHeartbeatTime) next_heartbeat_us_ = 0;
    }
  } else {
    reply.value = canopen::sdo_abort::kUnknownCommand;
  }
  if (reply.kind == SdoMessage::Kind::kAbort) ++counters_.sdo_aborts;
  SendLocked(canopen::SdoFrame(reply_id, reply));
}

uint32_t SimulatedCia402Drive::CheckPdoConfigWriteLocked(uint16_t index, uint8_t subindex,
                                                         uint32_t value) const {
  if (index != kRpdo1Mapping && index != kTpdo1Mapping) return 0;
  // CiA 301: a mapping changes only while its PDO is invalid, entries only while sub 0 is 0.
  const bool receive = index == kRpdo1Mapping;
  if (PdoValidLocked(receive ? kRpdo1Communication : kTpdo1Communication)) {
    return canopen::sdo_abort::kDeviceState;
  }
  if (subindex == 0) {
    if (value > 8) return canopen::sdo_abort::kPdoTooLong;
    uint32_t bits = 0;
    for (uint32_t sub = 1; sub <= value; ++sub) {
      bits += od_.Get(index, static_cast<uint8_t>(sub)) & 0xFF;
    }
    return bits > 64 ? canopen::sdo_abort::kPdoTooLong : 0;
  }
  if (od_.Get(index, 0) != 0) return canopen::sdo_abort::kDeviceState;
  if (value == 0) return 0;
  const PdoEntry entry = canopen::DecodePdoEntry(value);
  const OdEntry* object = od_.Find(entry.index, entry.subindex);
  const bool fits = object && object->mappable && entry.bits == object->size * 8 &&
                    (!receive || object->access == Access::kReadWrite);
  return fits ? 0 : canopen::sdo_abort::kNotMappable;
}

bool SimulatedCia402Drive::PdoValidLocked(uint16_t communication_index) const {
  return !(od_.Get(communication_index, 1) & canopen::kPdoInvalid);
}

void SimulatedCia402Drive::HandleRpdoLocked(const CanFrame& frame) {
  if (nmt_ != static_cast<uint8_t>(NmtState::kOperational)) return;
  if (od_.Get(kRpdo1Communication, 2) <= 240) {
    pending_rpdo_ = frame;  // synchronous: acts at the next SYNC
  } else {
    ApplyRpdoLocked(frame);
  }
}

void SimulatedCia402Drive::ApplyRpdoLocked(const CanFrame& frame) {
  const uint32_t count = od_.Get(kRpdo1Mapping, 0);
  std::vector<PdoEntry> entries;
  size_t bytes = 0;
  for (uint8_t sub = 1; sub <= count; ++sub) {
    entries.push_back(canopen::DecodePdoEntry(od_.Get(kRpdo1Mapping, sub)));
    bytes += entries.back().bits / 8;
  }
  if (bytes != frame.size) {
    ++counters_.emergencies;
    SendLocked(canopen::EmergencyFrame(options_.node_id, {kPdoLengthError, 0x11}));
    return;
  }
  size_t offset = 0;
  bool controlword = false;
  for (const PdoEntry& entry : entries) {
    od_.Set(entry.index, entry.subindex, canopen::GetLittleEndian(frame, offset, entry.bits / 8));
    offset += entry.bits / 8;
    controlword |= entry.index == cia402::kControlword;
  }
  ++counters_.rpdos;
  if (controlword) ProcessControlwordLocked();
}

void SimulatedCia402Drive::SendTpdoLocked() {
  UpdateStatuswordLocked();
  CanFrame frame{od_.Get(kTpdo1Communication, 1) & 0x7FF, 0, {}};
  const uint32_t count = od_.Get(kTpdo1Mapping, 0);
  for (uint8_t sub = 1; sub <= count; ++sub) {
    const PdoEntry entry = canopen::DecodePdoEntry(od_.Get(kTpdo1Mapping, sub));
    canopen::PutLittleEndian(&frame, frame.size, entry.bits / 8,
                             od_.Get(entry.index, entry.subindex));
    frame.size = static_cast<uint8_t>(frame.size + entry.bits / 8);
  }
  ++counters_.tpdos;
  SendLocked(frame);
}

void SimulatedCia402Drive::ProcessControlwordLocked() {
  const uint16_t controlword = static_cast<uint16_t>(od_.Get(cia402::kControlword, 0));
  const uint16_t previous = previous_controlword_;
  previous_controlword_ = controlword;
  const cia402::State before = state_;
  state_ = cia402::NextState(state_, controlword, previous);
  if (before == cia402::State::kFault && state_ != cia402::State::kFault) {
    od_.Set(cia402::kErrorCode, 0, 0);
    od_.Set(kErrorRegister, 0, 0);
    SendLocked(canopen::EmergencyFrame(options_.node_id, {0, 0}));  // error reset
  }
  const bool profile_position =
      od_.GetSigned(cia402::kModesOfOperationDisplay, 0) == cia402::kProfilePositionMode;
  if (state_ != cia402::State::kOperationEnabled || !profile_position) {
    motion_.Hold();
    setpoint_acknowledged_ = false;
  } else if ((controlword & cia402::controlword::kNewSetpoint) &&
             !(previous & cia402::controlword::kNewSetpoint)) {
    const double target = od_.GetSigned(cia402::kTargetPosition, 0);
    const bool relative = controlword & cia402::controlword::kRelative;
    motion_.target = relative ? motion_.target + target : target;
    setpoint_acknowledged_ = true;
    ++counters_.setpoints;
  } else if (!(controlword & cia402::controlword::kNewSetpoint)) {
    setpoint_acknowledged_ = false;
  }
  UpdateStatuswordLocked();
}

void SimulatedCia402Drive::EnterFaultLocked(uint16_t error_code) {
  state_ = cia402::State::kFault;  // the fault reaction (stop) is instantaneous here
  motion_.Hold();
  setpoint_acknowledged_ = false;
  od_.Set(cia402::kErrorCode, 0, error_code);
  od_.Set(kErrorRegister, 0, canopen::ErrorRegisterFor(error_code));
  UpdateStatuswordLocked();
  ++counters_.emergencies;
  SendLocked(canopen::EmergencyFrame(options_.node_id,
                                     {error_code, canopen::ErrorRegisterFor(error_code)}));
}

void SimulatedCia402Drive::AdvanceLocked(int64_t now_us) {
  const double dt = static_cast<double>(now_us - last_advance_us_) * 1e-6;
  last_advance_us_ = now_us;
  const uint16_t controlword = static_cast<uint16_t>(od_.Get(cia402::kControlword, 0));
  const bool halted = controlword & cia402::controlword::kHalt;
  if (state_ == cia402::State::kOperationEnabled && !halted) {
    motion_.Advance(dt, static_cast<double>(od_.Get(cia402::kProfileVelocity, 0)));
  }
  UpdateStatuswordLocked();
}

void SimulatedCia402Drive::UpdateStatuswordLocked() {
  const double position = std::round(motion_.position);
  od_.Set(cia402::kPositionActual, 0, static_cast<uint32_t>(static_cast<int32_t>(position)));
  uint16_t statusword = cia402::StatuswordBits(state_) | cia402::statusword::kRemote;
  const double window = od_.Get(cia402::kPositionWindow, 0);
  const bool halted = od_.Get(cia402::kControlword, 0) & cia402::controlword::kHalt;
  if (std::abs(motion_.target - motion_.position) <= window || halted) {
    statusword |= cia402::statusword::kTargetReached;
  }
  if (setpoint_acknowledged_) statusword |= cia402::statusword::kSetpointAcknowledge;
  od_.Set(cia402::kStatusword, 0, statusword);
}

void SimulatedCia402Drive::HeartbeatLocked(int64_t now_us) {
  const int64_t period_us = static_cast<int64_t>(od_.Get(kHeartbeatTime, 0)) * 1000;
  if (period_us == 0 || now_us < next_heartbeat_us_) return;
  next_heartbeat_us_ = now_us + period_us;
  SendLocked(canopen::HeartbeatFrame(options_.node_id, static_cast<NmtState>(nmt_)));
}

void SimulatedCia402Drive::SendLocked(const CanFrame& frame) {
  try {
    bus_->Send(frame);
  } catch (const CanBusError&) {
    // A cut cable: the frame is lost, as on a wire.
  }
}

cia402::State SimulatedCia402Drive::state() const {
  std::lock_guard lock(mutex_);
  return state_;
}

uint8_t SimulatedCia402Drive::nmt_state() const {
  std::lock_guard lock(mutex_);
  return nmt_;
}

int32_t SimulatedCia402Drive::position() const {
  std::lock_guard lock(mutex_);
  return static_cast<int32_t>(std::round(motion_.position));
}

int32_t SimulatedCia402Drive::setpoint() const {
  std::lock_guard lock(mutex_);
  return static_cast<int32_t>(std::round(motion_.target));
}

uint32_t SimulatedCia402Drive::Object(uint16_t index, uint8_t subindex) const {
  std::lock_guard lock(mutex_);
  return od_.Get(index, subindex);
}

SimulatedCia402Drive::Counters SimulatedCia402Drive::counters() const {
  std::lock_guard lock(mutex_);
  return counters_;
}

}  // namespace shapesense
