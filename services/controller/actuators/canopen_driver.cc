#include "services/controller/actuators/canopen_driver.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <thread>

#include "libs/actuation/canopen.h"
#include "runtime/devices/device_clock.h"

namespace shapesense {
namespace {

namespace cw = cia402::controlword;
namespace sw = cia402::statusword;
using canopen::PdoEntry;

constexpr uint16_t kHeartbeatTime = 0x1017;
constexpr uint16_t kRpdo1Communication = 0x1400;
constexpr uint16_t kRpdo1Mapping = 0x1600;
constexpr uint16_t kTpdo1Communication = 0x1800;
constexpr uint16_t kTpdo1Mapping = 0x1A00;
constexpr PdoEntry kRpdoEntries[] = {{cia402::kControlword, 0, 16},
                                     {cia402::kTargetPosition, 0, 32}};
constexpr PdoEntry kTpdoEntries[] = {{cia402::kStatusword, 0, 16},
                                     {cia402::kPositionActual, 0, 32}};
constexpr uint8_t kSynchronous = 1;  // PDO transmission type: at (after) every SYNC
constexpr auto kStatePollPause = std::chrono::milliseconds(1);

// What went wrong while talking, with the state it leaves the driver in.
class TroubleError : public std::runtime_error {
 public:
  TroubleError(ActuatorState state, uint32_t code, const std::string& what)
      : std::runtime_error(what), state_(state), code_(code) {}
  ActuatorState state() const { return state_; }
  uint32_t code() const { return code_; }

 private:
  ActuatorState state_;
  uint32_t code_;
};

std::string Hex(uint32_t value, int digits) {
  char text[16];
  std::snprintf(text, sizeof(text), "0x%0*X", digits, value);
  return text;
}

std::string Seconds(int64_t micros) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.2f s", static_cast<double>(micros) * 1e-6);
  return text;
}

uint32_t Counts(double mm_value, double counts_per_mm) {
  return static_cast<uint32_t>(std::max(1.0, std::round(mm_value * std::abs(counts_per_mm))));
}

}  // namespace

CanOpenActuatorDriver::CanOpenActuatorDriver(CanOpenOptions options, BusOpener open_bus,
                                             std::string bus_name)
    : options_(std::move(options)), open_bus_(std::move(open_bus)), bus_name_(std::move(bus_name)) {
  if (const std::string error = options_.Validate(); !error.empty()) {
    throw std::invalid_argument("canopen: " + error);
  }
  for (const int id : options_.node_ids) {
    Node node;
    node.id = id;
    nodes_.push_back(node);
  }
}

CanOpenActuatorDriver::~CanOpenActuatorDriver() { Disconnect(); }

std::string CanOpenActuatorDriver::NodeName(int id) const { return "node " + std::to_string(id); }

CanOpenActuatorDriver::Node* CanOpenActuatorDriver::FindNode(int id) {
  for (Node& node : nodes_) {
    if (node.id == id) return &node;
  }
  return nullptr;
}

// ---------------------------------------------------------------- faults

template <class Talk>
auto CanOpenActuatorDriver::Guarded(Talk&& talk) {
  try {
    return talk();
  } catch (const TroubleError& e) {
    Raise(e.state(), e.code(), bus_name_ + ": " + e.what());
  } catch (const SdoError& e) {
    const ActuatorState state =
        e.abort_code() == 0 ? ActuatorState::kDisconnected : ActuatorState::kFault;
    Raise(state, e.abort_code(), bus_name_ + ": " + e.what());
  } catch (const CanBusError& e) {
    Raise(ActuatorState::kDisconnected, 0, bus_name_ + ": " + e.what());
  }
  throw ActuatorError(status_.reason);
}

void CanOpenActuatorDriver::Raise(ActuatorState state, uint32_t code, const std::string& reason) {
  status_ = {state, reason, code};
  supervising_ = false;
  trouble_.reset();
  QuickStopAll();
}

void CanOpenActuatorDriver::QuickStopAll() {
  if (!bus_) return;
  try {
    for (const Node& node : nodes_) SendRpdo(node, cw::kQuickStop);
    bus_->Send(canopen::SyncFrame());  // synchronous RPDOs act at a SYNC
  } catch (const CanBusError& e) {
    if (status_.state == ActuatorState::kDisconnected) return;  // the reason says it already
    status_.state = ActuatorState::kDisconnected;
    status_.reason += std::string("; the quick stop did not go out: ") + e.what();
  }
}

void CanOpenActuatorDriver::RequireState(bool allow_fault, const char* action) const {
  const bool allowed = status_.state == ActuatorState::kOk ||
                       (allow_fault && status_.state == ActuatorState::kFault);
  if (allowed && bus_) return;
  throw ActuatorError(bus_name_ + ": " + action + " refused while " +
                      ActuatorStateName(status_.state) + " (" + status_.reason +
                      "); Connect() first");
}

// ---------------------------------------------------------------- receiving

void CanOpenActuatorDriver::Dispatch(const CanFrame& frame) {
  if (Node* node = FindNode(canopen::NodeOf(frame.id, canopen::kHeartbeatBase))) {
    OnHeartbeat(*node, frame.size > 0 ? frame.data[0] : 0xFF);
  } else if (Node* emcy = FindNode(canopen::NodeOf(frame.id, canopen::kEmcyBase))) {
    const canopen::Emergency emergency = canopen::ParseEmergency(frame);
    if (emergency.error_code == 0) return;  // an error reset
    emcy->last_emergency = "EMCY " + canopen::DescribeEmergency(emergency.error_code) +
                           ", error register " + Hex(emergency.error_register, 2);
    if (supervising_ && !trouble_) {
      trouble_ = Trouble{ActuatorState::kFault, emergency.error_code,
                         NodeName(emcy->id) + ": " + emcy->last_emergency};
    }
  } else if (Node* tpdo = FindNode(canopen::NodeOf(frame.id, canopen::kTpdo1Base))) {
    OnTpdo(*tpdo, frame);
  } else {
    return;  // not for this master (SDO of another client, other PDOs)
  }
  health_.last_contact_utime = EpochMicros();
}

void CanOpenActuatorDriver::OnHeartbeat(Node& node, uint8_t state) {
  node.nmt_state = state;
  node.last_heartbeat_us = SteadyMicros();
  if (state == static_cast<uint8_t>(canopen::NmtState::kBootUp)) node.booted = true;
  if (!supervising_ || trouble_ || state == static_cast<uint8_t>(canopen::NmtState::kOperational)) {
    return;
  }
  const std::string what = state == static_cast<uint8_t>(canopen::NmtState::kBootUp)
                               ? "restarted (boot-up message)"
                               : "left NMT operational (now " + canopen::NmtStateName(state) + ")";
  trouble_ = Trouble{ActuatorState::kFault, 0, NodeName(node.id) + " " + what};
}

void CanOpenActuatorDriver::OnTpdo(Node& node, const CanFrame& frame) {
  if (frame.size < 6) return;
  node.statusword = static_cast<uint16_t>(canopen::GetLittleEndian(frame, 0, 2));
  node.position = canopen::SignExtend(canopen::GetLittleEndian(frame, 2, 4), 4);
  node.tpdo_fresh = true;
  if (!supervising_ || trouble_) return;
  const cia402::State state = cia402::DecodeStatusword(node.statusword);
  if (state == cia402::State::kOperationEnabled) return;
  std::string what =
      state == cia402::State::kFault || state == cia402::State::kFaultReactionActive
          ? "drive fault"
          : std::string("left operation enabled (now ") + cia402::StateName(state) + ")";
  what += " (statusword " + Hex(node.statusword, 4) + ")";
  if (!node.last_emergency.empty()) what += "; last " + node.last_emergency;
  trouble_ = Trouble{ActuatorState::kFault, 0, NodeName(node.id) + ": " + what};
}

void CanOpenActuatorDriver::DrainBus() {
  for (int i = 0; i < 10000; ++i) {
    const std::optional<CanFrame> frame = bus_->Receive(std::chrono::microseconds(0));
    if (!frame) return;
    Dispatch(*frame);
  }
}

void CanOpenActuatorDriver::CheckHeartbeats() {
  if (!supervising_ || trouble_) return;
  const int64_t now_us = SteadyMicros();
  const int64_t timeout_us = SecondsToMicros(options_.heartbeat_timeout_s);
  for (const Node& node : nodes_) {
    const int64_t silent_us = now_us - node.last_heartbeat_us;
    if (silent_us <= timeout_us) continue;
    trouble_ = Trouble{ActuatorState::kFault, 0,
                       NodeName(node.id) + ": heartbeat lost (none for " + Seconds(silent_us) +
                           "; timeout " + Seconds(timeout_us) + ")"};
    return;
  }
}

void CanOpenActuatorDriver::Supervise() {
  DrainBus();
  CheckHeartbeats();
  if (trouble_) throw TroubleError(trouble_->state, trouble_->code, trouble_->reason);
}

// ---------------------------------------------------------------- PDO cycle

void CanOpenActuatorDriver::SendRpdo(const Node& node, uint16_t controlword) {
  CanFrame frame{canopen::kRpdo1Base + static_cast<uint32_t>(node.id), 6, {}};
  canopen::PutLittleEndian(&frame, 0, 2, controlword);
  canopen::PutLittleEndian(&frame, 2, 4, static_cast<uint32_t>(node.target));
  bus_->Send(frame);
}

bool CanOpenActuatorDriver::SyncRound() {
  for (Node& node : nodes_) node.tpdo_fresh = false;
  const auto all_fresh = [&] {
    return std::all_of(nodes_.begin(), nodes_.end(), [](const Node& n) { return n.tpdo_fresh; });
  };
  const int64_t sent_us = SteadyMicros();
  const int64_t deadline_us = sent_us + SecondsToMicros(options_.pdo_timeout_s);
  bus_->Send(canopen::SyncFrame());
  while (!all_fresh()) {
    const int64_t left_us = deadline_us - SteadyMicros();
    if (left_us <= 0) break;
    const std::optional<CanFrame> frame = bus_->Receive(std::chrono::microseconds(left_us));
    if (!frame) break;
    Dispatch(*frame);
  }
  if (!all_fresh()) return false;
  health_.round_trip_us = SteadyMicros() - sent_us;
  return true;
}

CanOpenActuatorDriver::Trouble CanOpenActuatorDriver::MissingTpdoTrouble() const {
  std::string missing;
  for (const Node& node : nodes_) {
    if (!node.tpdo_fresh) missing += (missing.empty() ? "" : ", ") + std::to_string(node.id);
  }
  const std::string tries = std::to_string(options_.pdo_retries + 1) + " tries of " +
                            std::to_string(static_cast<int>(options_.pdo_timeout_s * 1000)) + " ms";
  const bool none =
      std::none_of(nodes_.begin(), nodes_.end(), [](const Node& node) { return node.tpdo_fresh; });
  if (none) {
    return {ActuatorState::kDisconnected, 0, "no drive answered SYNC (" + tries + "): link lost?"};
  }
  return {ActuatorState::kFault, 0, "node " + missing + ": no TPDO1 after SYNC (" + tries + ")"};
}

int64_t CanOpenActuatorDriver::SyncUntil(const std::function<bool(const Node&)>& done,
                                         const char* what) {
  const int64_t deadline_us = SteadyMicros() + SecondsToMicros(options_.state_timeout_s);
  int missed = 0;
  do {
    const int64_t sync_utime = EpochMicros();
    const bool complete = SyncRound();
    if (trouble_) throw TroubleError(trouble_->state, trouble_->code, trouble_->reason);
    if (!complete) {
      ++health_.timeouts;
      if (++missed > options_.pdo_retries) {
        const Trouble trouble = MissingTpdoTrouble();
        throw TroubleError(trouble.state, trouble.code, trouble.reason);
      }
      ++health_.retries;
      continue;
    }
    if (std::all_of(nodes_.begin(), nodes_.end(), done)) return sync_utime;
  } while (SteadyMicros() < deadline_us);
  for (const Node& node : nodes_) {
    if (done(node)) continue;
    throw TroubleError(ActuatorState::kFault, 0,
                       NodeName(node.id) + ": no " + what + " within " +
                           Seconds(SecondsToMicros(options_.state_timeout_s)) + " (statusword " +
                           Hex(node.statusword, 4) + ")");
  }
  return EpochMicros();
}

// ---------------------------------------------------------------- bring-up

void CanOpenActuatorDriver::ResetAndAwaitBootUp() {
  for (Node& node : nodes_) {
    node.booted = false;
    node.last_emergency.clear();
    bus_->Send(canopen::NmtFrame(canopen::NmtCommand::kResetCommunication, node.id));
  }
  const int64_t deadline_us = SteadyMicros() + SecondsToMicros(options_.boot_timeout_s);
  const auto all_booted = [&] {
    return std::all_of(nodes_.begin(), nodes_.end(), [](const Node& n) { return n.booted; });
  };
  while (!all_booted()) {
    const int64_t left_us = deadline_us - SteadyMicros();
    if (left_us <= 0) break;
    const std::optional<CanFrame> frame = bus_->Receive(std::chrono::microseconds(left_us));
    if (!frame) break;
    Dispatch(*frame);
  }
  for (const Node& node : nodes_) {
    if (node.booted) continue;
    throw TroubleError(ActuatorState::kDisconnected, 0,
                       NodeName(node.id) + ": no boot-up message within " +
                           Seconds(SecondsToMicros(options_.boot_timeout_s)) +
                           " of the NMT reset (powered? node id? bit rate?)");
  }
}

void CanOpenActuatorDriver::MapPdo(int id, uint16_t communication, uint16_t mapping,
                                   uint32_t cob_id, std::span<const PdoEntry> entries) {
  // CiA 301 order: invalidate the PDO, empty its mapping, write the entries,
  // set their number, validate the PDO again.
  sdo_->Download(id, communication, 1, canopen::kPdoInvalid | cob_id, 4);
  sdo_->Download(id, communication, 2, kSynchronous, 1);
  sdo_->Download(id, mapping, 0, 0, 1);
  for (size_t i = 0; i < entries.size(); ++i) {
    sdo_->Download(id, mapping, static_cast<uint8_t>(i + 1), canopen::EncodePdoEntry(entries[i]),
                   4);
  }
  sdo_->Download(id, mapping, 0, static_cast<uint32_t>(entries.size()), 1);
  sdo_->Download(id, communication, 1, cob_id, 4);
}

void CanOpenActuatorDriver::CheckPdo(int id, uint16_t communication, uint16_t mapping,
                                     uint32_t cob_id, std::span<const PdoEntry> entries) {
  bool as_expected = sdo_->Upload(id, communication, 1) == cob_id &&
                     sdo_->Upload(id, mapping, 0) == entries.size();
  for (size_t i = 0; as_expected && i < entries.size(); ++i) {
    as_expected = canopen::DecodePdoEntry(sdo_->Upload(id, mapping, static_cast<uint8_t>(i + 1))) ==
                  entries[i];
  }
  if (as_expected) return;
  throw TroubleError(ActuatorState::kFault, 0,
                     NodeName(id) + ": PDO " + Hex(mapping, 4) + " is not mapped as " +
                         "docs/actuators.md expects (COB-ID " + Hex(cob_id, 3) +
                         "); set canopen.configure_pdos: true or map it so on the drive");
}

void CanOpenActuatorDriver::ConfigureNode(const Node& node) {
  const int id = node.id;
  const uint32_t device_type = sdo_->Upload(id, 0x1000, 0);
  if ((device_type & 0xFFFF) != cia402::kDeviceProfile) {
    throw TroubleError(
        ActuatorState::kFault, 0,
        NodeName(id) + ": not a CiA 402 drive (device type " + Hex(device_type, 8) + ")");
  }
  const uint32_t heartbeat_ms =
      static_cast<uint32_t>(std::lround(options_.heartbeat_period_s * 1000));
  sdo_->Download(id, kHeartbeatTime, 0, heartbeat_ms, 2);
  const uint32_t rpdo = canopen::kRpdo1Base + static_cast<uint32_t>(id);
  const uint32_t tpdo = canopen::kTpdo1Base + static_cast<uint32_t>(id);
  if (options_.configure_pdos) {
    MapPdo(id, kRpdo1Communication, kRpdo1Mapping, rpdo, kRpdoEntries);
    MapPdo(id, kTpdo1Communication, kTpdo1Mapping, tpdo, kTpdoEntries);
  } else {
    CheckPdo(id, kRpdo1Communication, kRpdo1Mapping, rpdo, kRpdoEntries);
    CheckPdo(id, kTpdo1Communication, kTpdo1Mapping, tpdo, kTpdoEntries);
  }
  sdo_->Download(id, cia402::kModesOfOperation, 0, cia402::kProfilePositionMode, 1);
  const int32_t mode =
      canopen::SignExtend(sdo_->Upload(id, cia402::kModesOfOperationDisplay, 0), 1);
  if (mode != cia402::kProfilePositionMode) {
    throw TroubleError(ActuatorState::kFault, 0,
                       NodeName(id) + ": did not take profile-position mode (6061h shows " +
                           std::to_string(mode) + ")");
  }
  const double cpm = options_.counts_per_mm;
  sdo_->Download(id, cia402::kProfileVelocity, 0, Counts(options_.profile_velocity_mm_s, cpm), 4);
  const uint32_t ramp = Counts(options_.profile_acceleration_mm_s2, cpm);
  sdo_->Download(id, cia402::kProfileAcceleration, 0, ramp, 4);
  sdo_->Download(id, cia402::kProfileDeceleration, 0, ramp, 4);
  sdo_->Download(id, cia402::kQuickStopDeceleration, 0,
                 Counts(options_.quick_stop_deceleration_mm_s2, cpm), 4);
}

cia402::State CanOpenActuatorDriver::ReadState(int id) {
  return cia402::DecodeStatusword(static_cast<uint16_t>(sdo_->Upload(id, cia402::kStatusword, 0)));
}

// Waits until the drive leaves `from`; the state it is in then.
cia402::State CanOpenActuatorDriver::AwaitStateChange(int id, cia402::State from,
                                                      const std::string& after) {
  const int64_t deadline_us = SteadyMicros() + SecondsToMicros(options_.state_timeout_s);
  for (;;) {
    const cia402::State state = ReadState(id);
    if (state != from) return state;
    if (SteadyMicros() > deadline_us) break;
    std::this_thread::sleep_for(kStatePollPause);
  }
  std::string what = NodeName(id) + " stays in " + cia402::StateName(from) + " " + after;
  if (from == cia402::State::kFault) {
    const uint32_t code = sdo_->Upload(id, cia402::kErrorCode, 0);
    what += " (error code " + canopen::DescribeEmergency(static_cast<uint16_t>(code)) + ")";
  }
  throw TroubleError(ActuatorState::kFault, 0, what);
}

void CanOpenActuatorDriver::EnableOperation(Node& node) {
  // Hold where it stands: the target is the actual position before the drive is enabled.
  node.position = canopen::SignExtend(sdo_->Upload(node.id, cia402::kPositionActual, 0), 4);
  node.target = node.position;
  sdo_->Download(node.id, cia402::kTargetPosition, 0, static_cast<uint32_t>(node.target), 4);
  cia402::State state = ReadState(node.id);
  for (int step = 0; step < 8 && state != cia402::State::kOperationEnabled; ++step) {
    const std::optional<uint16_t> controlword = cia402::ControlwordTowardOperationEnabled(state);
    std::string after = "(waiting for the drive)";
    if (controlword) {
      // A fault reset acts on the rising edge of bit 7.
      if (state == cia402::State::kFault) WriteControlword(node.id, cw::kDisableVoltage);
      WriteControlword(node.id, *controlword);
      after = "after controlword " + Hex(*controlword, 4);
    }
    state = AwaitStateChange(node.id, state, after);
  }
  if (state != cia402::State::kOperationEnabled) {
    throw TroubleError(ActuatorState::kFault, 0,
                       NodeName(node.id) + ": did not reach operation enabled (now " +
                           cia402::StateName(state) + ")");
  }
}

void CanOpenActuatorDriver::WriteControlword(int id, uint16_t controlword) {
  sdo_->Download(id, cia402::kControlword, 0, controlword, 2);
}

void CanOpenActuatorDriver::BringUp() {
  ResetAndAwaitBootUp();
  for (const Node& node : nodes_) ConfigureNode(node);
  for (const Node& node : nodes_) {
    bus_->Send(canopen::NmtFrame(canopen::NmtCommand::kStart, node.id));
  }
  for (Node& node : nodes_) EnableOperation(node);
  // From here on every heartbeat, EMCY and statusword counts.
  trouble_.reset();
  supervising_ = true;
  for (Node& node : nodes_) node.last_heartbeat_us = SteadyMicros();
  SyncUntil([](const Node&) { return true; }, "TPDO1");
}

// ---------------------------------------------------------------- the interface

void CanOpenActuatorDriver::Connect() {
  if (sdo_) health_.timeouts += sdo_->timeouts();
  sdo_.reset();
  bus_.reset();
  trouble_.reset();
  supervising_ = false;
  status_ = {ActuatorState::kDisconnected, bus_name_ + ": connecting", 0};
  try {
    bus_ = open_bus_();
  } catch (const CanBusError& e) {
    status_.reason = bus_name_ + ": " + e.what();
    throw ActuatorError(status_.reason);
  }
  sdo_ = std::make_unique<SdoClient>(
      *bus_, std::chrono::microseconds(SecondsToMicros(options_.sdo_timeout_s)),
      [this](const CanFrame& frame) { Dispatch(frame); });
  Guarded([&] { BringUp(); });
  status_ = {ActuatorState::kOk, "", 0};
  ++health_.connects;
}

void CanOpenActuatorDriver::Disconnect() {
  // The drives stay enabled and hold (halt): a tendon robot must not go limp.
  Stop();
  supervising_ = false;
  sdo_.reset();
  bus_.reset();
  status_ = {ActuatorState::kDisconnected, bus_name_ + ": disconnected by the controller", 0};
}

void CanOpenActuatorDriver::CommandTargets(std::span<const double> target_mm) {
  RequireState(/*allow_fault=*/false, "target");
  if (target_mm.size() != nodes_.size()) {
    throw ActuatorError(bus_name_ + ": expected " + std::to_string(nodes_.size()) +
                        " targets, got " + std::to_string(target_mm.size()));
  }
  std::vector<int32_t> counts;
  for (const double mm : target_mm) {
    const double value = std::round(mm * options_.counts_per_mm);
    if (!std::isfinite(value) || std::abs(value) > std::numeric_limits<int32_t>::max()) {
      throw ActuatorError(bus_name_ + ": target " + std::to_string(mm) +
                          " mm is no 32-bit position");
    }
    counts.push_back(static_cast<int32_t>(value));
  }
  Guarded([&] {
    Supervise();
    for (size_t i = 0; i < nodes_.size(); ++i) {
      nodes_[i].target = counts[i];
      SendRpdo(nodes_[i], cw::kEnableOperation | cw::kNewSetpoint | cw::kChangeSetImmediately);
    }
    SyncUntil([](const Node& n) { return (n.statusword & sw::kSetpointAcknowledge) != 0; },
              "set-point acknowledge");
    for (const Node& node : nodes_)
      SendRpdo(node, cw::kEnableOperation | cw::kChangeSetImmediately);
    SyncUntil([](const Node& n) { return (n.statusword & sw::kSetpointAcknowledge) == 0; },
              "end of the set-point handshake");
  });
}

ActuatorPositions CanOpenActuatorDriver::ReadPositions() {
  RequireState(/*allow_fault=*/true, "position read");
  return Guarded([&] {
    Supervise();
    ActuatorPositions positions;
    positions.utime = SyncUntil([](const Node&) { return true; }, "TPDO1");
    for (const Node& node : nodes_) {
      positions.mm.push_back(static_cast<double>(node.position) / options_.counts_per_mm);
    }
    return positions;
  });
}

ActuatorStatus CanOpenActuatorDriver::Status() {
  if (status_.state != ActuatorState::kOk || !bus_) return status_;
  try {
    Guarded([&] { Supervise(); });
  } catch (const ActuatorError&) {
    // The state says what happened.
  }
  return status_;
}

void CanOpenActuatorDriver::Stop() {
  if (!bus_ || status_.state == ActuatorState::kDisconnected) return;
  if (status_.state == ActuatorState::kFault) {
    QuickStopAll();
    return;
  }
  try {
    Guarded([&] {
      for (const Node& node : nodes_) SendRpdo(node, cw::kEnableOperation | cw::kHalt);
      SyncUntil([](const Node&) { return true; }, "TPDO1");
    });
  } catch (const ActuatorError&) {
    // Raise has quick-stopped what it could reach; the state says why.
  }
}

ActuatorHealth CanOpenActuatorDriver::Health() {
  ActuatorHealth health = health_;
  health.link_alive = bus_ && status_.state != ActuatorState::kDisconnected;
  if (sdo_) health.timeouts += sdo_->timeouts();
  return health;
}

}  // namespace shapesense
